"""Limited look-ahead over a particle belief, with the sampled GCM's values beyond it.

From a belief of weighted pose particles, every particle is simulated under every angle of Φ
to its next bump (`SampledModel.step`), then again from where it arrived, ``depth`` bumps deep.
The tree alternates the robot's choice of angle and what it then observes: after angle a the
particles that did not reach the goal split by the clock they read at the next bump, each group
a child belief (an observation node). Backwards, a particle's step is worth 1 if it reaches the
goal, else the value of its observation node — or, below the last level, whether it reaches the
goal when it follows the value iteration's policy on the GCM (`bounce_gym.markov.ssp.ReachPlan`)
for a few more bumps, simulated (`rollout`) — or, with no rollout bumps, the GCM's success value
of the state it arrived in (with one level, this is the QMDP rule: Littman, Cassandra & Kaelbling,
ICML 1995, on the particle belief); a node takes the best
angle (most likely success, then least plan cost, `ReachPlan.choose`). This is the limited
look-ahead policy of dynamic programming with a rollout of the GCM's policy as the cost-to-go
approximation (Bertsekas, *Dynamic Programming and Optimal Control*, vol. 1, §6.3–6.4), on the
belief tree of a POMDP with the simulator as the model (cf. Thrun, Burgard & Fox, 2005, ch. 15).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.markov.ssp import ReachPlan

#: the weight of the GCM's success value of a leaf's state beside its rollout's outcome: small,
#: so that it only breaks ties between leaves whose rollouts agree (e.g. all fail)
MODEL_WEIGHT = 1e-3

#: simulate(action, point, heading) -> outcomes, one per robot, and whether each reached the goal
Simulate = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[BumpOutcomes, np.ndarray]]


def lookahead(simulate: Simulate, plan: ReachPlan, point: np.ndarray, heading: np.ndarray,
              weight: np.ndarray, depth: int, steps_left: int, last: int | None,
              rollout_steps: int) -> int:
    """The best angle from the belief (``point``, ``heading``, ``weight`` summing to 1) with
    ``steps_left`` steps left and ``last`` the angle used last (None: none yet). Below the tree
    each particle is played out for ``rollout_steps`` more bumps (`rollout`; 0: the GCM's
    values instead)."""
    a_n = plan.n_actions
    depth = max(1, min(int(depth), int(steps_left)))
    node = np.zeros(len(point), dtype=np.int64)
    node_last = np.array([a_n if last is None else int(last)])
    levels = []
    for _ in range(depth):
        n = len(point)
        action = np.tile(np.arange(a_n), n)
        out, hit = simulate(action, np.repeat(point, a_n, axis=0), np.repeat(heading, a_n))
        parent = np.repeat(node, a_n)
        alive = ~hit & (out.next_state >= 0)
        key = np.column_stack((parent, action, out.ticks))[alive]
        unique, child = np.unique(key, axis=0, return_inverse=True)
        child_of = np.full(n * a_n, -1, dtype=np.int64)
        child_of[alive] = child.ravel()
        levels.append({"out": out, "hit": hit, "parent": parent, "action": action,
                       "weight": np.repeat(weight, a_n), "child": child_of,
                       "n_parents": len(node_last), "parent_last": node_last})
        point, heading = out.end[alive], out.heading[alive]
        weight, node, node_last = np.repeat(weight, a_n)[alive], child.ravel(), unique[:, 1]
        if len(point) == 0:
            break
    value_s = value_c = None
    change = (plan.w2 - plan.w1)
    for d in range(len(levels) - 1, -1, -1):
        lv = levels[d]
        out, hit, act = lv["out"], lv["hit"], lv["action"]
        h = steps_left - d  # steps left at this level's decision
        if value_s is None and rollout_steps <= 0:  # below the tree: the GCM's own values
            z = np.maximum(out.next_state, 0)
            later_s = plan.success[h - 1][z]
            later_c = plan.costs[h - 1][z, act]
        elif value_s is None:  # below the tree: rollouts, the GCM's values as tie-breakers
            later_s, later_c = rollout(simulate, plan, out.end, out.heading, out.next_state,
                                       act, min(h - 1, rollout_steps))
            # where rollouts tie (all fail), the model's own value of the state decides
            later_s = later_s + MODEL_WEIGHT * plan.success[h - 1][np.maximum(out.next_state, 0)]
        else:
            safe = np.maximum(lv["child"], 0)
            later_s, later_c = value_s[safe], value_c[safe]
        ok = lv["child"] >= 0
        reach = ok | (value_s is None) & (out.next_state >= 0)
        q_s = np.where(hit, 1.0, np.where(reach, later_s, 0.0))
        q_c = plan.w1 * (1.0 + out.ticks) + np.where(hit | (out.next_state < 0), 0.0, later_c)
        parent_last = lv["parent_last"][lv["parent"]]
        q_c = q_c + change * ((parent_last != act) & (parent_last < a_n))
        flat = lv["parent"] * a_n + act
        size = lv["n_parents"] * a_n
        mass = np.bincount(flat, weights=lv["weight"], minlength=size)
        mass = np.where(mass > 0, mass, 1.0)
        node_s = (np.bincount(flat, weights=lv["weight"] * q_s, minlength=size) / mass).reshape(
            -1, a_n)
        node_c = (np.bincount(flat, weights=lv["weight"] * q_c, minlength=size) / mass).reshape(
            -1, 1, a_n)
        best = plan.choose(node_s, node_c)[:, 0]
        rows = np.arange(len(best))
        value_s, value_c = node_s[rows, best], node_c[rows, 0, best]
    return int(best[0])


def rollout(simulate: Simulate, plan: ReachPlan, point: np.ndarray, heading: np.ndarray,
            state: np.ndarray, last: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Robots at bump poses (in decision ``state``, −1: none, after angle ``last``) play out
    up to ``steps`` bumps under each base policy — the value iteration's policy of their state,
    and each fixed angle of Φ — simulated; per robot the best base policy's outcome: whether it
    reaches the goal, and its plan cost on the way (the rollout algorithm with several base
    heuristics, Bertsekas, Tsitsiklis & Wu, J. Heuristics 3, 1997: their value, exact for the
    particle in a deterministic world, rather than the model's estimate of its state's)."""
    n, a_n = len(point), plan.n_actions
    k = a_n + 1  # base policy 0: the value iteration's; 1 + i: always angle i
    base = np.repeat(np.arange(k), n)
    point, heading = np.tile(point, (k, 1)), np.tile(heading, k)
    state = np.tile(np.asarray(state), k)
    last = np.tile(np.asarray(last, dtype=np.int64), k)
    success, cost = np.zeros(n * k), np.zeros(n * k)
    alive = state >= 0
    for t in range(steps):
        idx = np.flatnonzero(alive)
        if len(idx) == 0:
            break
        act = np.where(base[idx] == 0, plan.policy[steps - t, np.maximum(state[idx], 0),
                                                   last[idx]], base[idx] - 1).astype(np.int64)
        out, hit = simulate(act, point[idx], heading[idx])
        cost[idx] += plan.w1 * (1.0 + out.ticks) + (plan.w2 - plan.w1) * (act != last[idx])
        success[idx[hit]] = 1.0
        alive[idx] = ~hit & (out.next_state >= 0)
        point[idx], heading[idx], state[idx], last[idx] = out.end, out.heading, \
            out.next_state, act
    success, cost = success.reshape(k, n), cost.reshape(k, n)
    best = np.lexsort((cost, -success), axis=0)[0]
    cols = np.arange(n)
    return success[best, cols], cost[best, cols]
