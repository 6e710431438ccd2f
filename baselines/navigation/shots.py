"""The bounce angles whose next drive can pass through the goal, from geometry alone.

A robot at a bump pose (contact point p, heading h) under the relative rule turns to heading
h + θ with θ in the env's continuous range [lo, hi], then drives straight. The navigation task
counts the goal reached when that straight path enters the disk of radius r around the goal
point g with the heading within the tolerance τ of the goal heading γ
(`bounce_gym.envs.tasks.navigation.NavigationTask.ticks_to_goal`). Ignoring the walls between p
and the disk, the headings that do so form the intersection of three arcs:

* the directions from p into the disk, β ± asin(r / d) (β the bearing of g, d its distance;
  every direction when p lies in the disk);
* the headings the goal accepts, γ ± τ;
* the headings the robot can turn to, h + [lo, hi].

`shot_intervals` returns that intersection as an interval of bounce angles per pose (it is one
interval: the first two arcs are each narrower than a half-turn), `shot_angles` a few angles
spread inside it. Whether a wall blocks the drive before the disk is left to the simulator: the
search of `baselines.navigation.angle_search` simulates these angles beside its grid, so that a
goal hit that a grid of 1° steps would step over (the disk is 3.4° wide seen from 10 units) is
not missed. `ShotField` and `turn_gap` tell how far a pose is from having a shot, which ranks
the poses of a search that has to drop some.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.sparse import csgraph

from bounce_gym.cells.geodesic import GridGeodesic

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class GoalRegion:
    """The task's goal test: ``point`` (2,), ``heading`` γ, ``radius`` r and heading
    ``tolerance`` τ (radians)."""

    point: np.ndarray
    heading: float
    radius: float
    tolerance: float


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles reduced to (−π, π]."""
    return np.pi - np.mod(np.pi - angle, TWO_PI)


def _disk_arc(point: np.ndarray, goal: GoalRegion) -> tuple[np.ndarray, np.ndarray]:
    """Per pose, the bearing of the goal relative to γ and the half-width of the disk's arc
    (π where the pose lies in the disk: every direction)."""
    rel = goal.point - np.asarray(point, dtype=np.float64).reshape(-1, 2)
    distance = np.hypot(rel[:, 0], rel[:, 1])
    bearing = _wrap(np.arctan2(rel[:, 1], rel[:, 0]) - goal.heading)
    inside = distance <= goal.radius
    half = np.where(inside, np.pi, np.arcsin(np.minimum(1.0, goal.radius / np.maximum(
        distance, goal.radius))))
    return np.where(inside, 0.0, bearing), half


def shot_intervals(point: np.ndarray, heading: np.ndarray, goal: GoalRegion,
                   angle_range: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """(m,) lowest and highest bounce angle of each pose's shot at the goal (module docstring;
    NaN where there is none)."""
    lo, hi = angle_range
    bearing, half = _disk_arc(point, goal)
    # the first two arcs, relative to γ: the disk's (shifted by a turn where that meets [−τ, τ])
    u = np.full(len(bearing), np.nan)
    v = np.full(len(bearing), np.nan)
    for shift in (-TWO_PI, 0.0, TWO_PI):
        a, b = np.maximum(bearing + shift - half, -goal.tolerance), np.minimum(
            bearing + shift + half, goal.tolerance)
        meet = (a <= b) & np.isnan(u)
        u, v = np.where(meet, a, u), np.where(meet, b, v)
    # as bounce angles θ = γ + ψ − h, the interval starts at t0 in [0, 2π)
    t0 = np.mod(goal.heading + u - np.asarray(heading, dtype=np.float64), TWO_PI)
    t1 = t0 + (v - u)
    low, high = np.full(len(t0), np.nan), np.full(len(t0), np.nan)
    for shift in (0.0, TWO_PI):
        a, b = np.maximum(t0, lo + shift), np.minimum(t1, hi + shift)
        meet = (a <= b) & np.isnan(low)
        low, high = np.where(meet, a - shift, low), np.where(meet, b - shift, high)
    return low, high


def shot_angles(point: np.ndarray, heading: np.ndarray, goal: GoalRegion,
                angle_range: tuple[float, float], per_pose: int) -> np.ndarray:
    """(m, per_pose) bounce angles spread evenly inside each pose's shot interval (at the
    centres of ``per_pose`` equal parts; NaN rows where there is none)."""
    low, high = shot_intervals(point, heading, goal, angle_range)
    share = (np.arange(per_pose) + 0.5) / per_pose
    return low[:, None] + share[None, :] * (high - low)[:, None]


def turn_gap(heading: np.ndarray, goal: GoalRegion,
             angle_range: tuple[float, float]) -> np.ndarray:
    """(m,) radians by which the turns a robot can make from ``heading`` miss the headings the
    goal accepts (0: some turn ends within γ ± τ)."""
    lo, hi = angle_range
    turn = np.mod(goal.heading - np.asarray(heading, dtype=np.float64), TWO_PI)
    middle, width = 0.5 * (lo + hi), 0.5 * (hi - lo) + goal.tolerance
    return np.maximum(np.abs(_wrap(turn - middle)) - width, 0.0)


class ShotField:
    """How far a point is, through the free space, from a place with a clear shot at the goal.

    On the world's occupancy grid of side ``cell`` (for the robot's radius), a free cell is a
    *shot cell* when the straight segment from its centre to the goal point stays in the
    robot's configuration space (`World.eroded`, one vectorised shapely test per cell) and its
    bearing is within τ of γ plus the disk's half-width: a robot bumping there with a suitable heading has a shot. `distance` is the
    geodesic distance (`bounce_gym.cells.geodesic.GridGeodesic`, king moves) from a point's
    cell to the nearest shot cell; the search ranks its poses by it plus `turn_gap` — a
    cost-to-go estimate that knows the walls, where the bearing alone would send the search
    against them.
    """

    def __init__(self, world, robot_radius: float, goal: GoalRegion, cell: float) -> None:
        free = world.occupancy(cell, robot_radius)
        self.geodesic = GridGeodesic(free, cell, world.bounds[:2])
        rc = np.argwhere(free)
        x0, y0 = world.bounds[:2]
        centre = np.column_stack((x0 + (rc[:, 1] + 0.5) * cell, y0 + (rc[:, 0] + 0.5) * cell))
        bearing, half = _disk_arc(centre, goal)
        facing = centre[np.abs(bearing) <= half + goal.tolerance]
        space = world.eroded(robot_radius)
        shapely.prepare(space)
        sight = shapely.linestrings(np.stack(
            (facing, np.broadcast_to(goal.point, facing.shape)), axis=1))
        sources = self.geodesic.node_of(facing[shapely.covers(space, sight)])
        self.to_shot = (np.full(self.geodesic.n_nodes, np.inf) if len(sources) == 0 else
                        csgraph.dijkstra(self.geodesic.graph, directed=False,
                                         indices=np.unique(sources), min_only=True))

    def distance(self, point: np.ndarray) -> np.ndarray:
        """(m,) geodesic distance from each point to the nearest shot cell (inf: none)."""
        return self.to_shot[self.geodesic.node_of(point)]
