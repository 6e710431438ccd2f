"""Policies for ``bounce_gym/Drifter-v0`` (`baselines.policy.Policy` interface): the value
iteration policy of Alg. 5.5, and the always-drift and random-layer baselines.

The planner knows the model, as the thesis' planner does: at ``reset`` it takes the env's cell
model (``env.unwrapped.cell_model()``, the same on every backend) and the episode's goal (the
reach task's region, ``env.unwrapped.task.region.states``), solves Alg. 5.5 for them (cached per
model and goal) and then acts ``π(info["state"])``: the privileged model state of the drifter
that the env reports in ``info``. On the continuous backend that is the cell the drifter is in,
so the cell policy is executed open to the mismatch between the two dynamics.
"""

from __future__ import annotations

import numpy as np

from baselines.drifters.value_iteration import (
    ValueIterationResult,
    goal_states,
    reach_probability,
    value_iteration,
)
from baselines.policy import POSE_OBSERVED, Policy, episode_rng
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["AlwaysDriftPolicy", "RandomLayerPolicy", "ValueIterationPolicy", "state_from_info"]


def state_from_info(info) -> int:
    """The drifter's model state from a step's ``info`` (key ``"state"``)."""
    if not isinstance(info, dict) or "state" not in info:
        raise ConfigError("info: expected the env's info dict with the drifter's model state "
                          "under 'state' (bounce_gym/Drifter-v0 reports it)")
    return int(info["state"])


def reach_env(env, who: str):
    """The unwrapped ``Drifter-v0`` env with task "reach" that ``who`` plans for; `ConfigError`
    for any other env."""
    inner = env.unwrapped
    if getattr(getattr(inner, "task", None), "name", None) != "reach" \
            or not hasattr(inner, "cell_model"):
        raise ConfigError(f"env: {who} runs in bounce_gym/Drifter-v0 with task='reach'")
    return inner


class ValueIterationPolicy(Policy):
    """Alg. 5.5 executed in ``Drifter-v0``: π(state) of the value iteration for the episode's goal
    (module docstring).

    Args:
        gamma: as `value_iteration`; the reward is Eq. 5.10 whatever the env pays.
        form: as `value_iteration`.
        tol: as `value_iteration`.
        max_iterations: as `value_iteration`.

    Attributes:
        model: the env's cell model (after `reset`).
        result: the `ValueIterationResult` of the episode (after `reset`).
    """

    name = "value iteration"
    #: acts on ``info["state"]``, the drifter's true model state
    information = POSE_OBSERVED

    def __init__(self, gamma: float = 0.95, form: str = "thesis", tol: float = 1e-9,
                 max_iterations: int = 100_000) -> None:
        self.settings = dict(gamma=gamma, form=form, tol=tol, max_iterations=max_iterations)
        self.model: DrifterCells | None = None
        self.result: ValueIterationResult | None = None
        self._cache: dict[tuple[int, bytes], ValueIterationResult] = {}

    def plan(self, model: DrifterCells, goal) -> ValueIterationResult:
        """The value iteration for ``model`` and ``goal`` (cached), made the current plan."""
        goal = goal_states(model, goal)
        if model is not self.model:
            self._cache.clear()
            self.model = model
        key = (id(model), goal.tobytes())
        if key not in self._cache:
            self._cache[key] = value_iteration(model, goal, **self.settings)
        self.result = self._cache[key]
        return self.result

    def reset(self, env) -> None:
        inner = reach_env(env, "the value iteration policy")
        self.plan(inner.cell_model(), inner.task.region.states)

    def act(self, observation, info) -> int:
        if self.result is None:
            raise ConfigError("ValueIterationPolicy: call reset(env) or plan(model, goal) "
                              "before act")
        return int(self.result.policy[state_from_info(info)])

    def predicted_success(self, state: int, horizon: int | None = None) -> float:
        """The model's probability that the plan reaches the goal from ``state`` (within
        ``horizon`` steps, or ever)."""
        if self.result is None or self.model is None:
            raise ConfigError("ValueIterationPolicy: no plan yet")
        h = reach_probability(self.model, self.result.policy, self.result.goal, horizon)
        return float(h[int(state)])


class AlwaysDriftPolicy(Policy):
    """The passive drifter: never changes layer."""

    name = "always drift"

    def act(self, observation, info) -> int:
        return DRIFT


class RandomLayerPolicy(Policy):
    """A uniformly random legal action (drift, up or down) at every step, from
    ``info["action_mask"]``. The random stream restarts every episode from ``seed`` or, without
    one, from the episode's seed (`baselines.policy.episode_rng`)."""

    name = "random layer"

    def __init__(self, seed: int | None = None) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_rng(self.seed, seed)
        return None

    def act(self, observation, info) -> int:
        mask = info.get("action_mask") if isinstance(info, dict) else None
        if mask is None:
            raise ConfigError("info: expected the legal actions under 'action_mask'")
        return int(self.rng.choice(np.flatnonzero(np.asarray(mask, dtype=bool))))
