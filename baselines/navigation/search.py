"""Breadth-first search over the simulator from one known bump pose.

Without rotation noise the world is deterministic and a belief from contact and clock is one
exact pose. The shortest sequence of bounce angles that takes that pose to the goal can then be
searched for directly in the env's own dynamics: from the frontier of poses reached after k
bumps, every angle of Φ is simulated to the next bump in one batch (`SampledModel.step`), the
paths are tested against the goal region (`BumpOutcomes.goal_hits`), and poses reached before
are dropped (two poses equal to ``DIGITS`` decimals are one node). The first level with a hit
gives a shortest plan in bumps; among its hits the one of least plan cost (w1 per tick, w2 per
change of angle, Alam, Bobadilla & Shell 2017, Sec. IV-A, accumulated along the tree path) is
taken. This is uniform-cost search's breadth-first special case on the bump graph (Russell &
Norvig, *Artificial Intelligence*, 4th ed., §3.4), with the simulator as the successor function.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bounce_gym.cells.outcomes import BumpOutcomes

#: two bump poses equal to this many decimals (position and heading) are one search node
DIGITS = 9

#: simulate(action, point, heading) -> outcomes, one per robot, and whether each reached the goal
Simulate = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[BumpOutcomes, np.ndarray]]


@dataclass(frozen=True)
class SearchResult:
    """What `shortest_plan` found: the angles of a plan (indices into Φ), one per bump, and the
    poses the robot is expected at before each of them (``points[k]``, ``headings[k]``) — all
    empty when there is none; then ``exhausted`` tells that every pose reachable from the start
    was expanded within the limits, which proves the goal unreachable in this world."""

    actions: tuple[int, ...]
    points: np.ndarray
    headings: np.ndarray
    exhausted: bool = False

    @property
    def found(self) -> bool:
        return len(self.actions) > 0


def _none(exhausted: bool) -> SearchResult:
    return SearchResult((), np.zeros((0, 2)), np.zeros(0), exhausted)


def shortest_plan(simulate: Simulate, point: np.ndarray, heading: float, n_actions: int,
                  last: int | None, max_bumps: int, max_nodes: int, w1: float, w2: float
                  ) -> SearchResult:
    """The fewest bumps (at most ``max_bumps``) from the bump pose (``point``, ``heading``) to a
    path through the goal, least plan cost among those; no plan when none is found before
    ``max_bumps`` bumps or ``max_nodes`` expanded poses (`SearchResult.exhausted`: because there
    is none)."""
    points = [np.asarray(point, dtype=np.float64).reshape(1, 2)]
    headings = [np.array([float(heading)])]
    parents, actions, costs = [np.array([-1])], [np.array([-1])], [np.zeros(1)]
    last_of = np.array([n_actions if last is None else int(last)])
    seen = {_key(points[0][0], headings[0][0])}
    expanded = 0
    for _ in range(max_bumps):
        frontier_p, frontier_h = points[-1], headings[-1]
        n = len(frontier_p)
        if n == 0 or expanded >= max_nodes:
            return _none(n == 0)
        expanded += n
        act = np.tile(np.arange(n_actions), n)
        parent = np.repeat(np.arange(n), n_actions)
        out, hit = simulate(act, np.repeat(frontier_p, n_actions, axis=0),
                            np.repeat(frontier_h, n_actions))
        changed = (last_of[parent] != act) & (last_of[parent] < n_actions)
        cost = costs[-1][parent] + w1 * (1.0 + out.ticks) + (w2 - w1) * changed
        if hit.any():
            best = np.flatnonzero(hit)[np.argmin(cost[hit])]
            return _trace(points, headings, parents, actions, int(parent[best]), int(act[best]))
        keep = []
        for i in np.flatnonzero(out.next_state >= 0):
            key = _key(out.end[i], out.heading[i])
            if key not in seen:
                seen.add(key)
                keep.append(i)
        keep = np.asarray(keep, dtype=np.int64)
        points.append(out.end[keep])
        headings.append(out.heading[keep])
        parents.append(parent[keep])
        actions.append(act[keep])
        costs.append(cost[keep])
        last_of = act[keep]
    return _none(len(points[-1]) == 0)


def _key(point: np.ndarray, heading: float) -> tuple[float, float, float]:
    turn = float(heading) % (2 * np.pi)
    return (round(float(point[0]), DIGITS), round(float(point[1]), DIGITS), round(turn, DIGITS))


def _trace(points, headings, parents, actions, node: int, final: int) -> SearchResult:
    """The plan from the root to level-(len−1) node ``node``, then angle ``final``."""
    steps = [final]
    level = len(points) - 1
    at = [node]
    while level > 0:
        steps.append(int(actions[level][node]))
        node = int(parents[level][node])
        at.append(node)
        level -= 1
    at.reverse()
    levels = range(len(points))
    return SearchResult(tuple(reversed(steps)),
                        np.array([points[k][i] for k, i in zip(levels, at, strict=True)]),
                        np.array([headings[k][i] for k, i in zip(levels, at, strict=True)]))
