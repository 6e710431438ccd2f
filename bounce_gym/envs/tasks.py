"""Tasks: the part of an environment that owns reward, termination and task diagnostics.

The environment owns physics, observation and rendering; after every step it hands the task a
`StepEvents` record. Within one env step every robot rotates at most once (at the start) and then
drives straight, so its path is the segment ``start → end``; tasks integrate over it.

* `FreeTask` — no reward, never ends (rollouts, demos).
* `NavigationTask` — reach a goal pose; −w1 per tick, −(w2 − w1) per change of bounce angle, a
  bonus at the goal: the weights of the roadmap of Alam et al. (navigation paper Alg. 1, w1 = 1,
  w2 = 100).
* `CoverageTask` — match a target distribution over cells (uniform by default): reward for newly
  covered cells and for reducing the L2 distance between the visit histogram (time spent per cell)
  and the target (thesis §3.4.3, Eq. 3.8's objective).
* `LocalizationTask` — the robot starts at an unknown pose; a localization filter plugged in
  through ``filter_factory`` reports how much the robot can know.
* `MonitoringTask` (multi-robot) — each robot keeps to its own region; robot–robot contacts cost.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from bounce_gym.cells import CellModel, king_offset
from bounce_gym.dynamics.state import RobotState
from bounce_gym.errors import ConfigError


@dataclass
class StepEvents:
    """What happened to the m robots during one environment step."""

    ticks: int  # ticks elapsed
    start: np.ndarray  # (m, 2) positions at the start of the step
    end: np.ndarray  # (m, 2) positions at the end
    heading: np.ndarray  # (m,) heading while driving (after any rotation)
    bumps: np.ndarray  # (m,) bump ticks of each robot in this step
    angles: np.ndarray  # (m,) bounce angle (radians) each robot used; nan if it did not bump
    angle_changed: np.ndarray  # (m,) bool: a bump whose angle differs from the robot's last one
    robot_contact: np.ndarray  # (m,) bool: blocked by another robot at the end of the step


class Task:
    """Base class. Subclasses override what they need; the defaults describe the free task."""

    name = "free"
    #: keys this task accepts in ``reset(options=...)``
    option_keys: frozenset[str] = frozenset()

    def configure(self, options) -> None:
        """Bind to the environment's validated `EnvOptions` (world, robots, step length)."""
        self.options = options

    @property
    def observation_size(self) -> int:
        """Number of task features appended to each robot's observation (values in [-1, 1])."""
        return 0

    def start_poses(self, rng: np.random.Generator, options: Mapping) -> tuple | None:
        """Start (positions, headings) chosen by the task, or None for random poses."""
        return None

    def reset(self, state: RobotState, rng: np.random.Generator, options: Mapping) -> dict:
        """Start an episode on the placed robots; return task info."""
        return {}

    def step(self, state: RobotState, events: StepEvents) -> tuple[np.ndarray, np.ndarray, dict]:
        """Rewards (m,), terminated flags (m,) and task info for one step."""
        m = state.n_robots
        return np.zeros(m), np.zeros(m, dtype=bool), {}

    def observation(self, state: RobotState) -> np.ndarray:
        """(m, observation_size) task features."""
        return np.zeros((state.n_robots, 0), dtype=np.float32)

    def render_layers(self) -> dict:
        """Extra layers for the renderer (``goal``, ``heatmap``, ``regions``)."""
        return {}


FreeTask = Task


# -- helpers ----------------------------------------------------------------------------------

def _pose_option(options: Mapping, key: str, m: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Parse ``{"position": [x, y], "heading": rad}`` (or lists of them for m robots)."""
    value = options.get(key)
    if value is None:
        return None
    if not isinstance(value, Mapping) or set(value) - {"position", "heading"}:
        raise ConfigError(f"options[{key!r}]: expected a dict with 'position' and 'heading' "
                          f"(radians), got {value!r}")
    try:
        pos = np.asarray(value["position"], dtype=np.float64).reshape(m, 2)
        head = np.asarray(value["heading"], dtype=np.float64).reshape(m)
    except (KeyError, ValueError, TypeError):
        raise ConfigError(f"options[{key!r}]: needs 'position' ({m} x (x, y)) and 'heading' "
                          f"({m} angles, radians)") from None
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(head))):
        raise ConfigError(f"options[{key!r}]: position and heading must be finite")
    return pos, head


def tick_length(options, heading: np.ndarray) -> np.ndarray:
    """Distance one drive tick covers at each heading: ``step_length``, except on the cell
    backend, whose ticks are king moves — √2 cells along a diagonal."""
    heading = np.asarray(heading, dtype=np.float64)
    if options.backend != "cell":
        return np.full(heading.shape, options.step_length)
    dcol, drow = king_offset(heading)
    return options.step_length * np.hypot(dcol, drow)


def path_samples(events: StepEvents, step_length: np.ndarray | float, spacing: float):
    """Points along each robot's path with the ticks spent near each.

    Returns (robot index, points (n, 2), ticks (n,)): drive time is spread evenly along the
    segment (one tick per ``step_length``, a scalar or one per robot — see `tick_length`), each
    bump tick is spent at the start point, and the
    rest of the step (a robot standing blocked until the step ends) at the end point. The ticks
    of each robot add up to ``events.ticks``.
    """
    length = np.hypot(*(events.end - events.start).T)
    count = np.maximum(np.ceil(length / spacing).astype(int), 0)
    robot = np.repeat(np.arange(len(length)), count)
    frac = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count) + 0.5) / np.repeat(
        np.maximum(count, 1), count)
    pts = events.start[robot] + frac[:, None] * (events.end - events.start)[robot]
    step_length = np.broadcast_to(np.asarray(step_length, dtype=np.float64), length.shape)
    ticks = np.repeat(length / np.maximum(count, 1) / step_length, count)
    bumping = np.flatnonzero(events.bumps > 0)
    idle = events.ticks - events.bumps - length / step_length
    waiting = np.flatnonzero(idle > 1e-9)
    robot = np.concatenate((robot, bumping, waiting))
    pts = np.concatenate((pts, events.start[bumping], events.end[waiting]))
    ticks = np.concatenate((ticks, events.bumps[bumping].astype(float), idle[waiting]))
    return robot, pts, ticks


def _normalised(world, xy: np.ndarray) -> np.ndarray:
    xmin, ymin, xmax, ymax = world.bounds
    return (np.asarray(xy) - (xmin, ymin)) / (xmax - xmin, ymax - ymin) * 2 - 1


# -- navigation -------------------------------------------------------------------------------

class NavigationTask(Task):
    """Reach a goal pose: within ``goal_radius`` of the goal point, heading within tolerance.

    Args:
        start, goal: ``{"position": [x, y], "heading": radians}``; None draws one per episode
            (uniformly in the free space, or — on the cell backend — a random cell centre and
            bin heading).
            Both can also be given per episode through ``reset(options={"start": ..., "goal": ...})``.
        goal_radius: size of the goal region (default: one step length).
        heading_tolerance_deg: heading tolerance at the goal (default 22.5°, half a 45° bin).
        w1: cost per tick; w2: cost of a bump that changes the bounce angle (charged instead of
            w1). The first angle is free. Defaults are the paper's w1 = 1, w2 = 100.
        goal_bonus: reward on arrival.
        observe_task: append the start and goal poses (normalised) to the observation — the
            planners of the papers know both, so a fair RL agent needs them too.

    The goal counts as reached when the robot's straight path of a step passes through the goal
    region while its heading is within tolerance; only the ticks up to that point are charged.
    """

    name = "navigation"
    option_keys = frozenset({"start", "goal"})

    def __init__(self, start: Mapping | None = None, goal: Mapping | None = None,
                 goal_radius: float | None = None, heading_tolerance_deg: float = 22.5,
                 w1: float = 1.0, w2: float = 100.0, goal_bonus: float = 100.0,
                 observe_task: bool = True) -> None:
        self._fixed = {"start": start, "goal": goal}
        for key in ("start", "goal"):
            if self._fixed[key] is not None:
                _pose_option(self._fixed, key, 1)
        if not 0 < heading_tolerance_deg <= 180:
            raise ConfigError(f"heading_tolerance_deg: expected (0, 180], got {heading_tolerance_deg}")
        if goal_radius is not None and not goal_radius > 0:
            raise ConfigError(f"goal_radius: expected a number > 0, got {goal_radius}")
        if not (w1 >= 0 and w2 >= w1):
            raise ConfigError(f"w1, w2: expected 0 <= w1 <= w2, got w1={w1}, w2={w2}")
        self.goal_radius_arg = goal_radius
        self.heading_tolerance = math.radians(heading_tolerance_deg)
        self.w1, self.w2, self.goal_bonus = float(w1), float(w2), float(goal_bonus)
        self.observe_task = bool(observe_task)

    def configure(self, options) -> None:
        super().configure(options)
        if options.n_robots != 1:
            raise ConfigError("task 'navigation' is a single-robot task (n_robots must be 1)")
        self.goal_radius = float(self.goal_radius_arg or options.step_length)
        # on the cell backend, random starts and goals are cells (centre and bin heading): the
        # papers' x_I and x_G
        self._cells = None
        if options.backend == "cell":
            self._cells = CellModel(options.world, options.step_length,
                                    options.backend_options["n_bins"], options.robot_radius,
                                    options.backend_options["corner_rule"])
        for key, pose in self._fixed.items():
            if pose is not None:
                position = _pose_option(self._fixed, key, 1)[0]
                if not options.world.contains(position, options.robot_radius).all():
                    raise ConfigError(f"task_kwargs.{key}: position {position[0].tolist()} is "
                                      "not in the free space")

    @property
    def observation_size(self) -> int:
        return 8 if self.observe_task else 0

    def start_poses(self, rng, options):
        chosen = {k: _pose_option(options, k, 1) or _pose_option(self._fixed, k, 1)
                  for k in ("start", "goal")}
        world, radius = self.options.world, self.options.robot_radius
        for key in ("start", "goal"):
            if chosen[key] is None and self._cells is not None:
                p, k = rng.integers(self._cells.n_positions), rng.integers(self._cells.n_bins)
                chosen[key] = (self._cells.centres[[p]], np.array([k * self._cells.bin_width]))
            elif chosen[key] is None:
                chosen[key] = (world.sample_free(rng, 1, radius), rng.uniform(0, 2 * np.pi, 1))
            elif not world.contains(chosen[key][0], radius).all():
                raise ConfigError(f"{key} position {chosen[key][0][0].tolist()} is not in the "
                                  "free space")
        self.start, self.goal = chosen["start"], chosen["goal"]
        return self.start

    def reset(self, state, rng, options):
        self.last_angle = math.nan
        self.reached = False
        return self._info(state)

    def _info(self, state) -> dict:
        gap = float(np.hypot(*(state.position[0] - self.goal[0][0])))
        return {"goal_position": self.goal[0][0].copy(), "goal_heading": float(self.goal[1][0]),
                "distance_to_goal": gap, "is_success": self.reached}

    def _ticks_to_goal(self, events: StepEvents) -> float | None:
        """Ticks into the step at which the robot first enters the goal region, else None."""
        err = (events.heading[0] - self.goal[1][0] + np.pi) % (2 * np.pi) - np.pi
        if abs(err) > self.heading_tolerance:
            return None
        p0, p1, g = events.start[0], events.end[0], self.goal[0][0]
        seg = p1 - p0
        length = float(np.hypot(*seg))
        rel = p0 - g
        if rel @ rel <= self.goal_radius**2:
            s = 0.0
        elif length == 0:
            return None
        else:
            d = seg / length
            b = float(rel @ d)
            disc = b * b - (float(rel @ rel) - self.goal_radius**2)
            if disc < 0:
                return None
            s = -b - math.sqrt(disc)  # where the segment's line enters the goal disk
            if s < 0 or s > length:
                return None  # the disk lies behind the start, or beyond the end
        per_tick = float(tick_length(self.options, events.heading[:1])[0])
        drive = math.ceil(s / per_tick - 1e-9)
        return float(events.bumps[0] + drive)

    def step(self, state, events):
        changed = bool(events.angle_changed[0])
        arrive = self._ticks_to_goal(events)
        ticks = events.ticks if arrive is None else min(events.ticks, arrive)
        reward = -self.w1 * ticks - (self.w2 - self.w1) * changed
        info = self._info(state)
        if arrive is not None:
            self.reached = True
            reward += self.goal_bonus
            info.update(is_success=True, ticks_to_goal=int(state.ticks - events.ticks + arrive))
        info["angle_changed"] = changed
        return np.array([reward]), np.array([self.reached]), info

    def observation(self, state):
        if not self.observe_task:
            return np.zeros((1, 0), dtype=np.float32)
        feats = [_normalised(self.options.world, self.start[0][0]),
                 [math.cos(self.start[1][0]), math.sin(self.start[1][0])],
                 _normalised(self.options.world, self.goal[0][0]),
                 [math.cos(self.goal[1][0]), math.sin(self.goal[1][0])]]
        return np.concatenate(feats).astype(np.float32)[None, :]

    def render_layers(self):
        return {"goal": (*self.goal[0][0], self.goal_radius, float(self.goal[1][0]),
                         self.heading_tolerance)}


# -- coverage ---------------------------------------------------------------------------------

class CoverageTask(Task):
    """Cover the world to match a target distribution over cells.

    Args:
        target: None (uniform over free cells), an array (rows, cols) with row 0 at the bottom
            (the layout of `World.occupancy`), or a path to a ``.npy`` file of that array.
            Non-negative, positive total, zero on blocked cells; it is normalised to sum 1.
        cell_size: grid cell size (default: the step length, the cell of the papers' model).
        coverage_weight, distance_weight: reward = coverage_weight × (fraction of free cells
            newly visited) + distance_weight × (decrease of the L2 distance to the target).

    ``info`` reports ``coverage`` (fraction of free cells visited), ``distance`` (L2 between the
    normalised visit histogram — time spent per cell — and the target) and ``tv_distance``.
    """

    name = "coverage"

    def __init__(self, target: object = None, cell_size: float | None = None,
                 coverage_weight: float = 1.0, distance_weight: float = 1.0) -> None:
        self.target_arg = target
        self.cell_size_arg = cell_size
        if cell_size is not None and not cell_size > 0:
            raise ConfigError(f"cell_size: expected a number > 0, got {cell_size}")
        self.coverage_weight, self.distance_weight = float(coverage_weight), float(distance_weight)

    def configure(self, options) -> None:
        super().configure(options)
        self.cell_size = float(self.cell_size_arg or options.step_length)
        self.free = options.world.occupancy(self.cell_size, options.robot_radius)
        if not self.free.any():
            raise ConfigError("coverage: the world has no free cell of this size for this robot")
        self.target = self._target(self.target_arg)

    def _target(self, spec: object) -> np.ndarray:
        if spec is None:
            return self.free / self.free.sum()
        if isinstance(spec, str):
            try:
                spec = np.load(spec)
            except (OSError, ValueError) as exc:
                raise ConfigError(f"coverage target: cannot read {spec!r}: {exc}") from None
        target = np.asarray(spec, dtype=np.float64)
        if target.shape != self.free.shape:
            raise ConfigError(f"coverage target: expected shape {self.free.shape} (rows, cols of "
                              f"the cell grid), got {target.shape}")
        if not np.all(np.isfinite(target)) or np.any(target < 0) or target.sum() <= 0:
            raise ConfigError("coverage target: values must be finite, >= 0, with a positive sum")
        if np.any(target[~self.free] > 0):
            raise ConfigError("coverage target: puts mass on blocked cells")
        return target / target.sum()

    def reset(self, state, rng, options):
        self.visits = np.zeros(self.free.shape)
        self.visited = np.zeros(self.free.shape, dtype=bool)
        self.distance = float(np.hypot.reduce(self.target.ravel()))
        self._add(state.position, np.zeros(state.n_robots))
        return self._info()

    def _cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        xmin, ymin = self.options.world.bounds[:2]
        col = np.clip(((points[:, 0] - xmin) / self.cell_size).astype(int), 0, self.free.shape[1] - 1)
        row = np.clip(((points[:, 1] - ymin) / self.cell_size).astype(int), 0, self.free.shape[0] - 1)
        return row, col

    def _add(self, points: np.ndarray, ticks: np.ndarray) -> int:
        row, col = self._cells(points)
        np.add.at(self.visits, (row, col), ticks)
        new = ~self.visited[row, col] & self.free[row, col]
        self.visited[row, col] = True
        return int(len(set(zip(row[new].tolist(), col[new].tolist(), strict=True))))

    def _info(self) -> dict:
        total = self.visits.sum()
        hist = self.visits / total if total > 0 else self.visits
        return {"coverage": float(self.visited[self.free].mean()),
                "distance": float(np.hypot.reduce((hist - self.target).ravel())),
                "tv_distance": float(0.5 * np.abs(hist - self.target).sum())}

    def step(self, state, events):
        _, points, ticks = path_samples(events, tick_length(self.options, events.heading),
                                        self.cell_size / 4)
        new_cells = self._add(points, ticks)
        info = self._info()
        reward = (self.coverage_weight * new_cells / self.free.sum()
                  + self.distance_weight * (self.distance - info["distance"]))
        self.distance = info["distance"]
        m = state.n_robots
        return np.full(m, reward / m), np.zeros(m, dtype=bool), info

    def render_layers(self):
        origin = self.options.world.bounds[:2]
        return {"heatmap": (self.visits.copy(), origin, self.cell_size)}


# -- localization -----------------------------------------------------------------------------

class LocalizationTask(Task):
    """Global localization: the robot starts at an unknown pose and senses only bumps and time.

    Args:
        filter_factory: ``f(options) -> filter`` (or the import path ``"module:function"`` of
            one) building a localization filter for the env's validated `EnvOptions`. A filter
            has ``reset()``, ``update(symbol, angle)`` — symbol 1 for a bump tick (``angle`` the
            bounce angle used, radians), 0 for a forward tick — and the attributes ``size``
            (candidate configurations) and ``localized`` (in a knowledge cycle: localized up to
            the world's symmetry); optionally ``colour`` and ``trapped``. The combinatorial
            filters of Alam et al. plug in as ``"baselines.localization:task_filter"``.
        terminate_when_localized: end the episode once the filter reports ``localized``.

    The task feeds the filter the tick stream: the forward ticks of the drive that ``reset`` made
    (bounce mode), then per step its bump tick first and its forward ticks after. Without a
    filter it reports the sensed history (``info["observations"]``: (bump ticks, clock, angle or
    None) per step) and gives no reward. With one, ``info`` carries ``candidates``,
    ``localized`` (and ``colour``, ``trapped``) and the reward is the drop in log2(candidates).
    """

    name = "localization"

    def __init__(self, filter_factory: Callable | str | None = None,
                 terminate_when_localized: bool = True) -> None:
        if isinstance(filter_factory, str):
            filter_factory = _import(filter_factory, "filter_factory")
        if filter_factory is not None and not callable(filter_factory):
            raise ConfigError("filter_factory: expected a callable or 'module:function'")
        self.filter_factory = filter_factory
        self.terminate_when_localized = bool(terminate_when_localized)

    def configure(self, options) -> None:
        super().configure(options)
        self.filter = self.filter_factory(options) if self.filter_factory else None

    def reset(self, state, rng, options):
        self.history: list[tuple[int, int, float | None]] = []
        if self.filter is not None:
            self.filter.reset()
            for _ in range(int(state.clock[0])):  # the drive to the first contact (bounce mode)
                self.filter.update(0, None)
        return self._info()

    def _info(self) -> dict:
        info = {"observations": list(self.history)}
        if self.filter is not None:
            info.update(candidates=int(self.filter.size), localized=bool(self.filter.localized))
            for extra in ("colour", "trapped"):
                if hasattr(self.filter, extra):
                    info[extra] = getattr(self.filter, extra)
        return info

    def step(self, state, events):
        bumps = int(events.bumps[0])
        angle = None if math.isnan(events.angles[0]) else float(events.angles[0])
        self.history.append((bumps, int(state.clock[0]), angle))
        reward, done = 0.0, False
        if self.filter is not None:
            before = max(self.filter.size, 1)
            for _ in range(bumps):
                self.filter.update(1, angle)
            for _ in range(events.ticks - bumps):
                self.filter.update(0, None)
            reward = math.log2(before) - math.log2(max(self.filter.size, 1))
            done = self.terminate_when_localized and bool(self.filter.localized)
        return np.array([reward]), np.array([done]), self._info()


def _import(path: str, field: str):
    module, _, attr = path.partition(":")
    try:
        return getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError, ValueError):
        raise ConfigError(f"{field}: cannot import {path!r} (expected 'module:function')") from None


# -- monitoring (multi-robot) -----------------------------------------------------------------

class MonitoringTask(Task):
    """Persistent monitoring: robot i should stay in region i; contacts between robots cost.

    Args:
        regions: one polygon (list of (x, y)) per robot; default: the bounding box cut into
            vertical strips of equal width, intersected with the free space.
        contact_penalty: cost per robot–robot bump.

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

    def __init__(self, regions: list | None = None, contact_penalty: float = 1.0) -> None:
        self.regions_arg = regions
        self.contact_penalty = float(contact_penalty)

    def configure(self, options) -> None:
        super().configure(options)
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
                try:
                    poly = Polygon(ring)
                except (ValueError, TypeError):
                    raise ConfigError(f"regions[{k}]: expected a list of (x, y) points") from None
                if not poly.is_valid or poly.area <= 0:
                    raise ConfigError(f"regions[{k}]: not a valid polygon")
                polys.append(poly)
        self.regions = polys

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
        """Robot pairs together at ``points`` (m, 2): see the class docstring."""
        opts = self.options
        i, j = np.triu_indices(len(points), k=1)
        if opts.backend == "cell" or opts.robot_radius == 0:
            cells = np.floor((points - opts.world.bounds[:2]) / opts.step_length)
            together = np.all(cells[i] == cells[j], axis=1)
        else:
            together = np.hypot(*(points[i] - points[j]).T) < 2 * opts.robot_radius
        return int(together.sum())

    def render_layers(self):
        rings = []
        for poly in self.regions:
            parts = getattr(poly, "geoms", [poly])
            largest = max(parts, key=lambda p: p.area)
            rings.append(np.asarray(largest.exterior.coords))
        return {"regions": rings}


TASKS: dict[str, type[Task]] = {
    "free": FreeTask,
    "navigation": NavigationTask,
    "coverage": CoverageTask,
    "localization": LocalizationTask,
    "monitoring": MonitoringTask,
}


def make_task(task: object, task_kwargs: Mapping | None, allowed: tuple[str, ...]) -> Task:
    """A task from its name (plus keyword arguments) or an instance."""
    if isinstance(task, Task):
        if task_kwargs:
            raise ConfigError("task_kwargs: only allowed together with a task name")
        if task.name not in allowed:
            raise ConfigError(f"task: {task.name!r} is not available here; allowed: {list(allowed)}")
        return task
    if task not in allowed:
        raise ConfigError(f"task: expected one of {list(allowed)} or a Task, got {task!r}")
    if task_kwargs is not None and not isinstance(task_kwargs, Mapping):
        raise ConfigError(f"task_kwargs: expected a dict, got {task_kwargs!r}")
    try:
        return TASKS[task](**dict(task_kwargs or {}))
    except TypeError as exc:
        raise ConfigError(f"task_kwargs for {task!r}: {exc}") from None
