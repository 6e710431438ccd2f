"""Reaching a goal within the horizon on a (sampled) drifter model: finite-horizon value
iteration, and a policy that acts on what the drifter observes.

**Plan.** The objective the reach task measures is the probability of entering the goal within
H steps (`bounce_gym.envs.drifters.tasks.ReachTask`). On a model whose step k has action
matrices ``A_k^u`` (`SampledDrifterCells.action_matrices`, time-dependent where the currents
are; the same every step for the exact `DrifterCells`), backward induction (value iteration over
the H stages; Bertsekas & Tsitsiklis 1991 for the reach-probability objective) gives it exactly:
``V_H = 0``, ``V_k(x) = max_u Σ_y A_k^u(x, y) [1_G(y) + (1 - 1_G(y)) V_{k+1}(y)]`` over the
legal u, ties to the lowest action code; ``V_0(x)`` is the model's predicted success from x.

**Acting.** `HorizonReachPolicy` decides from the drifter's observation only: its layer, its
clock (the step k) and its position, which the env observes with ``observe_pose=True``
(`bounce_gym.envs.drifters.core.DrifterCore.observed_pose`), looked up in the model's (sub-)cells;
``info`` is never read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from baselines.drifters.policy import reach_env
from baselines.drifters.value_iteration import goal_states
from baselines.policy import POSE_OBSERVED, Policy
from bounce_gym import validate
from bounce_gym.cells import DrifterCells
from bounce_gym.cells.sampled_drifter import SampledDrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["HorizonPlan", "HorizonReachPolicy", "horizon_plan"]


@dataclass(frozen=True, eq=False)
class HorizonPlan:
    """The finite-horizon plan (module docstring).

    Attributes:
        values: (H + 1, N) ``V_k``: the probability of reaching the goal in the remaining
            ``H - k`` steps from each state (row H is 0; 0 on the goal, which ends the episode).
        policy: (H, N) int64 action codes of step k.
        goal: the goal states, ascending.
        horizon: H.
    """

    values: np.ndarray
    policy: np.ndarray
    goal: np.ndarray
    horizon: int

    def predicted_success(self, state: int) -> float:
        """The model's probability of reaching the goal within the horizon from ``state``
        (1 if it starts in the goal)."""
        return 1.0 if np.isin(state, self.goal) else float(self.values[0, int(state)])


def horizon_plan(model: DrifterCells, goal, horizon: int) -> HorizonPlan:
    """Backward induction over ``horizon`` steps on ``model`` for ``goal`` (module docstring;
    ``goal`` as `goal_states`)."""
    if not isinstance(model, DrifterCells):
        raise ConfigError(f"model: expected a DrifterCells, got {type(model).__name__}")
    horizon = validate.integer("horizon", horizon, 1)
    goal = goal_states(model, goal)
    n = model.n_states
    in_goal = np.zeros(n, dtype=bool)
    in_goal[goal] = True
    illegal = ~model.legal.T  # (3, N)
    stacks: dict[int, sp.csr_matrix] = {}
    values = np.zeros((horizon + 1, n))
    policy = np.zeros((horizon, n), dtype=np.int64)
    for k in range(horizon - 1, -1, -1):
        key = _step_key(model, k)
        if key not in stacks:
            matrices = (model.action_matrices(key) if isinstance(model, SampledDrifterCells)
                        else model.action_matrices())
            stacks[key] = sp.vstack(matrices, format="csr")
        after = np.where(in_goal, 1.0, values[k + 1])
        q = (stacks[key] @ after).reshape(3, n)
        q[illegal] = -np.inf
        policy[k] = np.argmax(q, axis=0)
        values[k] = np.where(in_goal, 0.0, q.max(axis=0))
    policy[:, goal] = 0
    for arr in (values, policy, goal):
        arr.flags.writeable = False
    return HorizonPlan(values=values, policy=policy, goal=goal, horizon=horizon)


def _step_key(model: DrifterCells, k: int) -> int:
    """The index of the matrices of step k (steps past the model's last share its matrices)."""
    if isinstance(model, SampledDrifterCells):
        return min(k, model.n_steps - 1)
    return 0


class HorizonReachPolicy(Policy):
    """Finite-horizon value iteration on the env's sampled cell model, acting on the drifter's
    observation (module docstring). Needs ``bounce_gym/Drifter-v0`` with ``task="reach"`` and
    ``observe_pose=True``.

    Args:
        horizon: the episode's horizon H (steps).
        samples: of the sampled model (`DrifterEnvBase.cell_model`); None takes its default.
        seed: of the sampled model.
        refine: of the sampled model.

    Attributes:
        model, plan: the episode's model and `HorizonPlan` (after `reset`).
    """

    name = "value iteration (sampled GCM)"
    #: acts on the true position the observation holds (``observe_pose``)
    information = POSE_OBSERVED

    def __init__(self, horizon: int, samples: int | None = None, seed: int = 0,
                 refine: int = 1) -> None:
        self.horizon = validate.integer("horizon", horizon, 1)
        self.samples, self.seed, self.refine = samples, seed, refine
        self.model: DrifterCells | None = None
        self.plan: HorizonPlan | None = None
        self._plans: dict[bytes, HorizonPlan] = {}
        self._decode = None

    def reset(self, env) -> None:
        inner = reach_env(env, "the sampled value iteration policy")
        task = inner.task
        if not inner.options.observe_pose:
            raise ConfigError("env_kwargs.observe_pose: the sampled value iteration policy "
                              "acts on the observed position; set observe_pose=True")
        model = inner.cell_model(kind="sampled", samples=self.samples, seed=self.seed,
                                 horizon=self.horizon, refine=self.refine)
        exact = inner.cell_model()
        if model is not self.model:
            self._plans.clear()
            self.model = model
            # the env's cell of every (sub-)cell of the model
            self._parent = exact.state_at_point(*model.centre(np.arange(model.n_states)),
                                                model.cells[:, 0])
        key = np.asarray(task.region.states).tobytes()
        if key not in self._plans:
            goal = np.flatnonzero(np.isin(self._parent, task.region.states))
            self._plans[key] = horizon_plan(model, goal, self.horizon)
        self.plan = self._plans[key]
        self._exact = exact
        self._decode = inner.core.observed_pose

    def act(self, observation, info) -> int:
        if self.plan is None:
            raise ConfigError("HorizonReachPolicy: call reset(env) before act")
        x, y, layer, step = self._decode(np.asarray(observation)[None])
        state = int(self.model.state_at_point(x, y, layer)[0])
        return int(self.plan.policy[min(int(step[0]), self.horizon - 1), state])

    def predicted_success(self, state: int) -> float:
        """The model's probability that the plan reaches the goal from the centre of the env's
        cell ``state`` (where the env deploys a drifter)."""
        if self.plan is None:
            raise ConfigError("HorizonReachPolicy: no plan yet")
        x, y = self._exact.centre(np.array([state]))
        fine = self.model.state_at_point(x, y, self._exact.cells[[state], 0])
        return self.plan.predicted_success(int(fine[0]))
