"""The task interface and helpers shared by the tasks."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bounce_gym.cells import king_offset, king_step
from bounce_gym.dynamics.state import RobotState
from bounce_gym.errors import ConfigError
from bounce_gym.validate import numbers


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

    def configure(self, core) -> None:
        """Bind to the environment's `BounceCore`: its validated `EnvOptions` (``core.options``:
        world, robots, step length) and its discrete model (``core.cell_model()``)."""
        self.options = core.options

    @property
    def observation_labels(self) -> tuple[str, ...]:
        """What each task feature appended to a robot's observation is (values in [-1, 1]), in
        order; none by default."""
        return ()

    @property
    def observation_size(self) -> int:
        """Number of task features appended to each robot's observation."""
        return len(self.observation_labels)

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

def pose_option(options: Mapping, key: str, m: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Parse ``{"position": [x, y], "heading": rad}`` (or lists of them for m robots)."""
    value = options.get(key)
    if value is None:
        return None
    if not isinstance(value, Mapping) or set(value) - {"position", "heading"}:
        raise ConfigError(f"options[{key!r}]: expected a dict with 'position' and 'heading' "
                          f"(radians), got {value!r}")
    if set(value) != {"position", "heading"}:
        raise ConfigError(f"options[{key!r}]: needs 'position' ({m} x (x, y)) and 'heading' "
                          f"({m} angles, radians)")
    pos = numbers(f"options[{key!r}]['position']", value["position"])
    head = numbers(f"options[{key!r}]['heading']", value["heading"])
    if pos.size != 2 * m or head.size != m:
        raise ConfigError(f"options[{key!r}]: needs 'position' ({m} x (x, y)) and 'heading' "
                          f"({m} angles, radians)")
    return pos.reshape(m, 2), head.reshape(m)


def tick_length(options, heading: np.ndarray) -> np.ndarray:
    """Distance one drive tick covers at each heading: ``step_length``, except on the cell
    backend, whose ticks are king moves — √2 cells along a diagonal."""
    heading = np.asarray(heading, dtype=np.float64)
    if options.backend != "cell":
        return np.full(heading.shape, options.step_length)
    dcol, drow = king_offset(heading)
    return options.step_length * np.hypot(dcol, drow)


def tick_length_at(options, heading: float) -> float:
    """`tick_length` of one heading, in Python floats (`king_step`)."""
    if options.backend != "cell":
        return float(options.step_length)
    dcol, drow = king_step(heading)
    return options.step_length * math.hypot(dcol, drow)


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


