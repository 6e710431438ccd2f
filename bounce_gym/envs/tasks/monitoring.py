"""Persistent monitoring: every robot keeps to its own region."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from bounce_gym.dynamics.backends.base import close_pairs
from bounce_gym.envs.tasks.base import Task, path_samples, tick_length
from bounce_gym.errors import ConfigError
from bounce_gym.validate import flag, number, numbers


class MonitoringTask(Task):
    """Persistent monitoring: robot i should stay in region i; contacts between robots cost.

    Args:
        regions: one polygon (list of (x, y)) per robot; default: the bounding box cut into
            vertical strips of equal width, intersected with the free space.
        contact_penalty: cost per robot–robot bump.
        observe_region: add robot i's region to its observation — the region's bounding box
            (x_min, y_min, x_max, y_max), each scaled from the world's bounds to [-1, 1]. Part
            of the task's statement, like a navigation goal; the robot still does not sense
            where it is, so this adds no sensing.

    Reward of robot i per step: the fraction of the step's ticks it spent in its region minus
    ``contact_penalty`` if it ended the step blocked by another robot.

    ``info`` per step: ``in_region_fraction`` (per robot, the share of the step's ticks spent in
    its region), ``robot_contacts`` (robots that ended the step blocked by another robot) and
    ``encounters`` — robot pairs that are together at the end of the step: closer than
    2 · robot_radius, or, on the ``cell`` backend or with radius 0, in the same position cell
    (cell size = step_length). With ``robot_collisions="ignore"`` robots pass through each
    other, so encounters are the collisions Algorithm 2's accepted cycles avoid.
    """

    name = "monitoring"

    def __init__(self, regions: list | None = None, contact_penalty: float = 1.0,
                 observe_region: bool = False) -> None:
        if regions is not None:
            if isinstance(regions, str | bytes) or not isinstance(regions, Sequence | np.ndarray):
                raise ConfigError(f"regions: expected a list of polygons (lists of (x, y) "
                                  f"points), got {regions!r}")
            regions = [_ring(f"regions[{k}]", ring) for k, ring in enumerate(regions)]
        self.regions_arg = regions
        self.contact_penalty = number("contact_penalty", contact_penalty)
        self.observe_region = flag("observe_region", observe_region)

    def configure(self, core) -> None:
        super().configure(core)
        options = self.options
        world, m = options.world, options.n_robots
        if self.regions_arg is None:
            xmin, ymin, xmax, ymax = world.bounds
            edges = np.linspace(xmin, xmax, m + 1)
            polys = [world.polygon.intersection(box(a, ymin, b, ymax))
                     for a, b in zip(edges[:-1], edges[1:], strict=True)]
        else:
            if len(self.regions_arg) != m:
                raise ConfigError(f"regions: expected {m} polygons (one per robot), "
                                  f"got {len(self.regions_arg)}")
            polys = []
            for k, ring in enumerate(self.regions_arg):
                poly = Polygon(ring)
                if not poly.is_valid or poly.area <= 0:
                    raise ConfigError(f"regions[{k}]: not a valid polygon")
                polys.append(poly)
        self.regions = polys
        xmin, ymin, xmax, ymax = world.bounds
        low, size = np.array([xmin, ymin] * 2), np.array([xmax - xmin, ymax - ymin] * 2)
        bounds = np.array([poly.bounds for poly in polys], dtype=np.float64)
        self._features = np.clip(2 * (bounds - low) / size - 1, -1, 1).astype(np.float32)

    @property
    def observation_labels(self) -> tuple[str, ...]:
        """With ``observe_region``: the bounding box of the robot's region, scaled to [-1, 1]
        over the world's bounds."""
        if not self.observe_region:
            return ()
        return ("region x min", "region y min", "region x max", "region y max")

    def observation(self, state):
        return self._features.copy() if self.observe_region else super().observation(state)

    def reset(self, state, rng, options):
        return {"in_region": self._inside(state.position).tolist()}

    def _inside(self, points: np.ndarray, robots: np.ndarray | None = None) -> np.ndarray:
        robots = np.arange(len(points)) if robots is None else robots
        out = np.zeros(len(points), dtype=bool)
        for i, poly in enumerate(self.regions):
            sel = robots == i
            out[sel] = shapely.intersects_xy(poly, points[sel, 0], points[sel, 1])
        return out

    def step(self, state, events):
        robot, points, ticks = path_samples(events, tick_length(self.options, events.heading),
                                            self.options.step_length / 4)
        inside = self._inside(points, robot)
        m = state.n_robots
        time_in = np.bincount(robot, weights=ticks * inside, minlength=m)
        total = max(events.ticks, 1)
        rewards = time_in / total - self.contact_penalty * events.robot_contact
        info = {"in_region_fraction": (time_in / total).tolist(),
                "robot_contacts": int(events.robot_contact.sum()),
                "encounters": self._encounters(events.end)}
        return rewards, np.zeros(m, dtype=bool), info

    def _encounters(self, points: np.ndarray) -> int:
        """Robot pairs together at ``points`` (m, 2): see the class docstring. Pairs are counted
        per shared cell, or among the pairs within 2R along both axes, not over all pairs."""
        opts = self.options
        if opts.backend == "cell" or opts.robot_radius == 0:
            cells = np.floor((points - opts.world.bounds[:2]) / opts.step_length)
            _, count = np.unique(cells.astype(np.int64), axis=0, return_counts=True)
            return int((count * (count - 1) // 2).sum())
        gap = 2 * opts.robot_radius
        i, j = close_pairs(points, gap)
        return int(np.count_nonzero(np.hypot(*(points[i] - points[j]).T) < gap))

    def render_layers(self):
        rings = []
        for poly in self.regions:
            parts = getattr(poly, "geoms", [poly])
            largest = max(parts, key=lambda p: p.area)
            rings.append(np.asarray(largest.exterior.coords))
        return {"regions": rings}


def _ring(field: str, ring: object) -> np.ndarray:
    """A polygon's points as an (n, 2) array of finite numbers, n >= 3."""
    points = numbers(field, ring)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 3:
        raise ConfigError(f"{field}: expected a list of at least 3 (x, y) points, got {ring!r}")
    return points
