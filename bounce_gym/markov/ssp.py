"""Reaching a goal on a generalized cell mapping: a finite-horizon stochastic shortest path.

The chain is the GCM of bump states under a choice of bounce angle (`bounce_gym.cells.outcomes`):
from state z with angle a the robot reaches the goal during the drive with probability
``hit[z, a]``, bumps next in z' without having reached it with probability ``P_a[z, z']`` (rows
may lose mass: samples that never bumped again), and pays ``cost[z, a]`` (the ticks of the step)
plus, when a differs from the angle it used last, the angle-change surcharge — the plan cost of
Alam, Bobadilla & Shell (IRC 2017, Sec. IV-A): w1 per tick, w2 instead of w1 for a bump that
changes the angle, the first angle free.

`ReachPlan` solves, by backward value iteration over the remaining steps h = 1 … H (Bertsekas &
Tsitsiklis, "An analysis of stochastic shortest path problems", Math. Oper. Res. 16(3), 1991;
finite-horizon form of Bertsekas, *Dynamic Programming and Optimal Control*, vol. 1, ch. 1), the
lexicographic problem: first maximise the probability of reaching the goal within h steps,

    S_h(z) = max_a  hit[z, a] + Σ_z' P_a[z, z'] S_{h−1}(z'),     S_0 = 0,

then, among the angles within ``tie`` of that maximum, minimise the expected plan cost
C_h(z, ℓ) accumulated within the horizon (ℓ: the last angle, |Φ| meaning none yet). The values
of every h are kept: a policy with a limited look-ahead uses them as the cost-to-go beyond it
(Bertsekas, *Dynamic Programming and Optimal Control*, vol. 1, §6.3).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

#: success probabilities within this of the best count as ties (broken by cost)
TIE = 1e-6


class ReachPlan:
    """The lexicographic finite-horizon values of a goal on a GCM (module docstring).

    Args:
        hit: (N, |Φ|) probability of reaching the goal in the step.
        miss: per angle, the (N, N) sub-stochastic matrix of the next bump state, goal missed.
        cost: (N, |Φ|) expected ticks of the step.
        horizon: H, the most steps.
        w1: the plan-cost weight of a step.
        w2: the plan-cost weight that replaces w1 for a bump that changes the angle.
    """

    def __init__(self, hit: np.ndarray, miss: list[sp.csr_matrix], cost: np.ndarray,
                 horizon: int, w1: float = 1.0, w2: float = 100.0, tie: float = TIE) -> None:
        self.hit, self.miss, self.cost = hit, miss, cost
        self.horizon, self.w1, self.w2, self.tie = int(horizon), float(w1), float(w2), float(tie)
        n, a = hit.shape
        self.n_actions = a
        #: (H + 1, N) success values S_h
        self.success = np.zeros((self.horizon + 1, n))
        #: (H + 1, N, |Φ| + 1) cost values C_h(z, ℓ)
        self.costs = np.zeros((self.horizon + 1, n, a + 1))
        #: (H + 1, N, |Φ| + 1) the optimal angle with h steps left in z after angle ℓ
        self.policy = np.zeros((self.horizon + 1, n, a + 1), dtype=np.int8)
        for h in range(1, self.horizon + 1):
            q_s, q_c = self._q(h, slice(None))
            best = self.choose(q_s, q_c)
            self.policy[h] = best
            self.success[h] = np.take_along_axis(q_s, best[:, :1], axis=1)[:, 0]
            self.costs[h] = np.take_along_axis(q_c, best[:, :, None], axis=2)[:, :, 0]

    def _q(self, h: int, states) -> tuple[np.ndarray, np.ndarray]:
        """Q-values with h steps left at ``states``: success (n, |Φ|) and cost (n, |Φ|+1, |Φ|)."""
        a = self.n_actions
        q_s = np.column_stack([self.hit[states, i] + self.miss[i][states] @ self.success[h - 1]
                               for i in range(a)])
        future = np.column_stack([self.miss[i][states] @ self.costs[h - 1][:, i]
                                  for i in range(a)])
        change = np.ones((a + 1, a)) - np.eye(a + 1, a)
        change[a] = 0.0  # the first angle is free
        q_c = (self.w1 * self.cost[states] + future)[:, None, :] \
            + (self.w2 - self.w1) * change[None, :, :]
        return q_s, q_c

    def follow(self, h: int, steps: int) -> np.ndarray:
        """The probability of reaching the goal within ``steps`` steps when every decision takes
        the angle that is best with ``h`` steps left (``policy[h]``: a receding horizon of h
        bumps), by policy evaluation on the chain: (N, |Φ| + 1), per state and last angle."""
        a = self.n_actions
        chosen = self.policy[min(int(h), self.horizon)].astype(np.int64)  # (N, |Φ| + 1)
        value = np.zeros((self.hit.shape[0], a + 1))
        for _ in range(int(steps)):
            per_action = np.column_stack([self.hit[:, i] + self.miss[i] @ value[:, i]
                                          for i in range(a)])
            value = np.take_along_axis(per_action, chosen, axis=1)
        return value

    def choose(self, q_s: np.ndarray, q_c: np.ndarray) -> np.ndarray:
        """The best angles for success values ``q_s`` (n, |Φ|) and cost values ``q_c``
        (n, m, |Φ|): most likely success (within `TIE`), then least cost; (n, m)."""
        near = q_s >= q_s.max(axis=1, keepdims=True) - self.tie
        return np.argmin(np.where(near[:, None, :], q_c, np.inf), axis=2)
