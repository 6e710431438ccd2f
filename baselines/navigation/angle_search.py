"""Breadth-first search over bump poses with continuous bounce angles, in the simulator.

Without rotation noise the robot's pose at a bump is known exactly from its start and the
clocks it read, and the world is deterministic; the angles that take it to the goal can then be
searched for in the env's own dynamics. From the frontier of poses reached after k bumps every
pose is bumped, in one batch, with

* every angle of a fine grid over the continuous range (e.g. 2° steps), and
* a few angles inside its *shot interval*, where the drive would pass through the goal disk
  with an accepted heading if no wall were in the way (`baselines.navigation.shots`): the
  refinement around goal hits that a grid alone would step over,

each rounded to the angle its float32 action executes (`baselines.navigation.motion`). The
simulated straight paths are tested against the goal region (`BumpOutcomes.goal_hits`, the
task's own test); the first level with a hit gives a plan of fewest bumps, the hit with fewest
ticks among them. Otherwise the poses the bumps arrived at form the next frontier: two poses on
one cell of a fine grid (``GRID`` units, ``GRID`` radians) are one node (the first found is
kept, exactly), and when more than ``frontier`` remain, half of them are those of least
``score`` (the planner's estimate of the way left, e.g. `ShotField.distance` plus `turn_gap`),
the other half drawn at random from the rest so that the search does not crowd into one
corner. The tree path of every node is simulated exactly, so a
plan found is exact; the grid only prunes.

This is breadth-first search on the bump graph (Russell & Norvig, *Artificial Intelligence*,
4th ed., §3.4.1) with the simulator as the successor function, its frontier bounded as in beam
search (ibid., §4.1.3). It cannot prove a goal unreachable: the angles are a sample of a
continuum. When it finds no plan it returns the way to its frontier pose nearest a shot, which
the planner follows before searching again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from baselines.navigation.motion import exact_angles
from baselines.navigation.shots import GoalRegion, shot_angles

#: score(points, headings) -> (m,): a pose's estimated way left to the goal (less is better)
Score = Callable[[np.ndarray, np.ndarray], np.ndarray]

#: side of the grid cells (world units and radians) that make two poses one search node
GRID = 1e-3


@dataclass(frozen=True)
class AngleBudget:
    """What one search may spend: ``grid`` bounce angles (radians) tried from every pose,
    ``shots`` angles inside every pose's shot interval, at most ``frontier`` poses per level,
    ``bumps`` levels and ``nodes`` expanded poses in all."""

    grid: np.ndarray
    shots: int = 3
    frontier: int = 300
    bumps: int = 6
    nodes: int = 2_000


@dataclass(frozen=True)
class AnglePlan:
    """A sequence of bounce angles (radians, as executed) and the bump poses the robot is at
    before each (``points[k]``, ``headings[k]``); ``found``: the last angle's drive passes
    through the goal (else the sequence leads to the search's most promising pose, the bump
    pose ``end_point``, ``end_heading``; NaN when found or empty)."""

    angles: np.ndarray
    points: np.ndarray
    headings: np.ndarray
    found: bool
    end_point: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    end_heading: float = float("nan")

    def then(self, other: AnglePlan) -> AnglePlan:
        """This plan followed by ``other``, searched from this one's end pose."""
        return AnglePlan(np.concatenate((self.angles, other.angles)),
                         np.concatenate((self.points, other.points)),
                         np.concatenate((self.headings, other.headings)), other.found,
                         other.end_point, other.end_heading)


def search_angles(motion, point: np.ndarray, heading: float, goal: GoalRegion,
                  angle_range: tuple[float, float] | None, budget: AngleBudget, max_bumps: int,
                  score: Score, rng: np.random.Generator, max_ticks: int) -> AnglePlan:
    """The fewest bumps (at most ``max_bumps`` and ``budget.bumps``) from the bump pose
    (``point``, ``heading``) to a drive through the goal (module docstring); ``motion``:
    ``bumps(angles, action, point, heading, rng, max_ticks)`` as in
    `bounce_gym.dynamics.bump_table.bump_motion`. Without a plan, the way to the last level's
    pose of least ``score``. ``angle_range``: the continuous action's range, whose float32
    actions the angles are rounded to; None for discrete angles, tried as they are (and no
    shots: ``budget.shots`` must be 0)."""
    points = [np.asarray(point, dtype=np.float64).reshape(1, 2)]
    headings = [np.array([float(heading)])]
    parents, angles = [np.array([-1])], [np.array([np.nan])]
    seen = {_key(points[0], headings[0])[0]}
    grid = np.asarray(budget.grid, dtype=np.float64) if angle_range is None \
        else exact_angles(budget.grid, angle_range)
    expanded = 0
    for _ in range(min(int(max_bumps), budget.bumps)):
        fp, fh = points[-1], headings[-1]
        n = len(fp)
        if n == 0 or expanded >= budget.nodes:
            break
        expanded += n
        shots = np.zeros(0) if angle_range is None else exact_angles(
            shot_angles(fp, fh, goal, angle_range, budget.shots), angle_range)
        has = ~np.isnan(shots)
        angle = np.concatenate((shots[has], np.tile(grid, n)))
        parent = np.concatenate((np.nonzero(has)[0], np.repeat(np.arange(n), len(grid))))
        out = motion.bumps(angle, np.arange(len(angle)), fp[parent], fh[parent], rng, max_ticks)
        hit = out.goal_hits(goal.point, goal.heading, goal.radius, goal.tolerance)
        if hit.any():
            best = np.flatnonzero(hit)[np.argmin(out.ticks[hit])]
            return _trace(points, headings, parents, angles, int(parent[best]),
                          float(angle[best]), True)
        keep = _new(out.end, out.heading, out.next_state >= 0, seen)
        keep = _select(keep, score(out.end[keep], out.heading[keep]), budget.frontier, rng)
        points.append(out.end[keep])
        headings.append(out.heading[keep])
        parents.append(parent[keep])
        angles.append(angle[keep])
    if len(points) == 1 or len(points[-1]) == 0:
        return AnglePlan(np.zeros(0), np.zeros((0, 2)), np.zeros(0), False)
    last = len(points) - 1
    node = int(np.argmin(score(points[last], headings[last])))
    plan = _trace(points[:last], headings[:last], parents[:last], angles[:last],
                  int(parents[last][node]), float(angles[last][node]), False)
    return replace(plan, end_point=points[last][node], end_heading=float(headings[last][node]))


def _key(point: np.ndarray, heading: np.ndarray) -> list[tuple[int, int, int]]:
    cells = np.column_stack((point / GRID, np.mod(heading, 2 * np.pi) / GRID))
    return [tuple(row) for row in np.round(cells).astype(np.int64).tolist()]


def _new(end: np.ndarray, heading: np.ndarray, arrived: np.ndarray, seen: set) -> np.ndarray:
    """The indices of the arrived poses on grid cells not seen before (one per cell)."""
    keep = []
    index = np.flatnonzero(arrived)
    for i, key in zip(index.tolist(), _key(end[index], heading[index]), strict=True):
        if key not in seen:
            seen.add(key)
            keep.append(i)
    return np.asarray(keep, dtype=np.int64)


def _select(keep: np.ndarray, score: np.ndarray, size: int, rng: np.random.Generator
            ) -> np.ndarray:
    """At most ``size`` of the new poses: half of least score, half at random from the rest."""
    if len(keep) <= size:
        return keep
    order = np.argsort(score, kind="stable")
    best, rest = order[: size // 2], order[size // 2:]
    drawn = rng.choice(rest, size - len(best), replace=False)
    return keep[np.sort(np.concatenate((best, drawn)))]


def _trace(points, headings, parents, angles, node: int, final: float, found: bool
           ) -> AnglePlan:
    """The plan from the root to level-(len − 1) node ``node``, then angle ``final``."""
    steps, at = [final], []
    level = len(points) - 1
    while level >= 0:
        at.append((level, node))
        if level > 0:
            steps.append(float(angles[level][node]))
        node = int(parents[level][node])
        level -= 1
    at.reverse()
    return AnglePlan(np.array(steps[::-1]), np.array([points[k][i] for k, i in at]),
                     np.array([headings[k][i] for k, i in at]), found)
