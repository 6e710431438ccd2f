"""A fleet policy for ``bounce_gym/MultiDrifter-v0``: release the drifters at the cells of a
deployment of the surface, then let every one of them drift (`baselines.policy.MultiPolicy`).

This is the deployment problem of Alam 2018 (thesis §5.3.2, problem 1): the drifters are
passive, and all that is chosen is where they start. ``method`` names the deployment:

* ``"alg5.2"`` — `deployment_locations` (Alg. 5.2), its random cell per persistent group drawn
  from the episode's seed; it fixes the fleet size (`DeploymentPolicy.size`);
* ``"random"`` — `random_deployment`: as many distinct surface cells as the env has drifters,
  uniformly from the episode's seed;
* ``"greedy"`` — `greedy_deployment` for ``horizon`` steps, as many cells as the env has
  drifters (the same every episode).

Like `ValueIterationPolicy`, the policy takes the env's cell model
(``env.unwrapped.cell_model()``), whatever the backend. The deployment of the episode is
``deployment`` after `start_options`.
"""

from __future__ import annotations

from baselines.drifters.behavior import PersistentBehavior, persistent_behavior
from baselines.drifters.deployment import Deployment, deploy_cells, deployment_locations
from baselines.drifters.deployment_baselines import greedy_deployment, random_deployment
from baselines.policy import MultiPolicy
from bounce_gym import validate
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["DEPLOYMENT_METHODS", "RANDOM_DEPLOYMENT", "DeploymentPolicy"]

#: The deployments `DeploymentPolicy` releases a fleet at.
DEPLOYMENT_METHODS = ("alg5.2", "random", "greedy")
#: The layer the fleet is released in and covers (MultiDrifter-v0 covers the surface).
SURFACE = 0


#: the row name of the random deployment (the baseline the others are compared with)
RANDOM_DEPLOYMENT = "random deployment"


class DeploymentPolicy(MultiPolicy):
    """Release the fleet at a deployment's cells and drift (module docstring).

    Args:
        method: one of `DEPLOYMENT_METHODS`.
        horizon: the greedy deployment's horizon in steps (``"greedy"`` only; required there).
    """

    def __init__(self, method: str, horizon: int | None = None) -> None:
        if method not in DEPLOYMENT_METHODS:
            raise ConfigError(f"method: expected one of {DEPLOYMENT_METHODS}, got {method!r}")
        if (method == "greedy") != (horizon is not None):
            raise ConfigError("horizon: the greedy deployment needs one (steps), the others "
                              "take none")
        self.method = method
        self.horizon = None if horizon is None else validate.integer("horizon", horizon, 1)
        self.name = {"alg5.2": "Alg. 5.2 deployment", "random": RANDOM_DEPLOYMENT,
                     "greedy": f"greedy deployment (H={horizon})"}[method]
        self.deployment: Deployment | None = None
        self._model: DrifterCells | None = None
        self._behavior: PersistentBehavior | None = None
        self._greedy: dict[int, Deployment] = {}

    def behavior(self, model: DrifterCells) -> PersistentBehavior:
        """Alg. 5.1 on the surface layer of ``model`` (kept while the model is the same)."""
        if model is not self._model:
            self._model, self._behavior, self._greedy = model, persistent_behavior(model,
                                                                                   SURFACE), {}
        return self._behavior

    @staticmethod
    def size(behavior: PersistentBehavior) -> int:
        """The number of drifters Alg. 5.2 deploys in the layer of ``behavior``."""
        return len(deployment_locations(behavior, seed=0))

    def choose(self, behavior: PersistentBehavior, n: int, seed: int) -> Deployment:
        """The deployment of ``n`` drifters for the episode with ``seed``."""
        if self.method == "alg5.2":
            chosen = deployment_locations(behavior, seed=seed)
            if len(chosen) != n:
                raise ConfigError(f"env_kwargs.n_drifters: Alg. 5.2 deploys {len(chosen)} "
                                  f"drifters on this field's surface, the env has {n}; set "
                                  f"n_drifters to {len(chosen)}")
            return chosen
        if self.method == "random":
            return random_deployment(behavior, n, seed=seed)
        if n not in self._greedy:
            self._greedy[n] = greedy_deployment(behavior, n, self.horizon)
        return self._greedy[n]

    def start_options(self, env, seed: int) -> dict:
        inner = env.unwrapped
        if not hasattr(inner, "cell_model") or not hasattr(inner, "possible_agents"):
            raise ConfigError("env: the deployment policy runs in bounce_gym/MultiDrifter-v0")
        model = inner.cell_model()
        self.deployment = self.choose(self.behavior(model), len(inner.possible_agents), seed)
        return {"deploy": deploy_cells(model, self.deployment.states)}

    def act(self, observations, infos) -> dict:
        return dict.fromkeys(observations, DRIFT)
