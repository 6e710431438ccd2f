"""The environments' constructor arguments: one table, one parser, one place for their docs.

`BounceEnv` and the multi-robot envs (`MultiBounceEnv`, `MultiBounceAEC`) take the same keyword
arguments, listed with their defaults in `ARGUMENTS`; each env passes `parse_options` a small
dict of its own defaults and the arguments it does not take. Angles enter in **degrees** here
(this is the configuration edge of the package) and are stored in radians. An unknown argument
raises `TypeError` naming it; every bad value raises `ConfigError` naming the argument and what is
allowed.

Arguments (defaults of the single-robot env; the multi-robot envs start from ``grid_15x15``,
4 robots of radius 0.3 and ``robot_collisions="bounce"``):

* ``world``: zoo name (`bounce_gym.worlds.names()`), map-file path, or `World`.
* ``task``: a task name or a `Task` (see `bounce_gym.envs.tasks`; single robot: ``"free"``,
  ``"navigation"``, ``"coverage"``, ``"localization"``; multi-robot: ``"free"``, ``"coverage"``,
  ``"monitoring"``); ``task_kwargs``: keyword arguments of the task class.
* ``backend``: ``"kinematic"`` (exact, continuous), ``"pymunk"`` (physics engine) or ``"cell"``
  (the papers' discrete cell-to-cell model: cell size = ``step_length``, ``cell_bins``
  orientation bins, ``corner_rule``; relative rule and discrete actions whose angles are whole
  bins; one tick = one cell step or one rotation).
* ``physics``: ``"ideal"`` (the papers' exact model: straight drives at one cell per tick,
  rotations within a tick) or ``"dynamic"`` (rigid bodies with mass, motors of limited
  acceleration and turn rate, a bumper, friction and restitution:
  `bounce_gym.dynamics.backends.pymunk_dynamic`). None (default): ``"dynamic"`` on the pymunk
  backend, ``"ideal"`` on the others, which have only that one.
* ``physics_params``: with ``physics="dynamic"``, a dict of the physical parameters of
  `bounce_gym.dynamics.platform.PhysicsParams` (SI units, angles in degrees; defaults: an iRobot
  Create 2 and ``world_scale`` = 1 metre per world unit), e.g. ``{"cruise_speed": 0.3,
  "friction": 0.0}``.
* ``bounce_rule``: ``"relative"`` (Alam), ``"fixed"``, ``"specular"``, ``"monotonic"``,
  ``"nilles_relative"`` (Nilles).
* ``angles``: the set Φ, in degrees (default 45, 90, 135); multi-robot: also one set per robot,
  as a list of sets or a ``{"robot_i": ...}`` dict.
* ``angle_range``: (low, high) degrees for continuous actions (default: min/max of Φ); per robot
  like ``angles``.
* ``noise``: None, ``{"type": "reliable", "r": 0.8, "eps_deg": 5}`` or
  ``{"type": "interval", "lo_deg": -5, "hi_deg": 5}``.
* ``robot_radius`` (default None: a point, or with ``physics="dynamic"`` — where point robots
  do not exist — the Create 2's 0.17 m in world units, 0.17 / ``world_scale``),
  ``step_length`` (default 1: one cell per tick; with ``physics="dynamic"`` the distance
  driven in one tick at cruise speed).
* ``step_mode``: ``"bounce"`` (one step = the bump, then driving to the next contact) or
  ``"tick"`` (one step = one tick).
* ``action_type``: ``"discrete"`` or ``"continuous"``.
* ``history``: number of (segment ticks, angle) pairs in the observation (default 0, at most
  `MAX_HISTORY` = 10 000: far more bounces than any episode of the papers' experiments has).
* ``privileged``: add the true pose to the observation (default False).
* ``cell_bins``, ``corner_rule``: orientation bins (default 8) and diagonal rule (default
  ``"target_only"``, see `bounce_gym.cells.model`) of the env's cell model — the cell backend's
  grid, and the model the env hands planners on every backend (``env.cell_model()``).
* multi-robot only: ``n_robots`` (at most 10,000: one PettingZoo agent each);
  ``robot_collisions`` (``"bounce"`` | ``"ignore"``);
  ``turn_angles`` (degrees; extra discrete actions that turn a robot in place, parallel form
  only); ``min_sep_cells`` (``cell`` backend: robots within this Chebyshev distance collide,
  0 = the same cell).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from bounce_gym import worlds
from bounce_gym.cells import CORNER_RULES
from bounce_gym.dynamics.backends.base import ROBOT_COLLISIONS
from bounce_gym.dynamics.noise import NoiseModel, make_noise
from bounce_gym.dynamics.platform import PLATFORM_RADIUS, PhysicsParams, physics_params
from bounce_gym.dynamics.rules import RULES, check_parameters
from bounce_gym.dynamics.simulator import PHYSICS
from bounce_gym.errors import ConfigError, InvalidWorldError
from bounce_gym.validate import integer, keyword_arguments
from bounce_gym.validate import number as _number
from bounce_gym.worlds import World

BACKENDS = ("kinematic", "pymunk", "cell")
#: Largest ``history`` (observation length grows by 2 per entry).
MAX_HISTORY = 10_000
#: Largest ``n_robots`` of an env (every robot is a PettingZoo agent with its own dicts; the
#: batched dynamics, `bounce_gym.dynamics.BounceDynamics`, takes more).
MAX_ROBOTS = 10_000
STEP_MODES = ("bounce", "tick")
ACTION_TYPES = ("discrete", "continuous")


#: Every constructor argument of the environments, with the single-robot env's defaults.
ARGUMENTS: dict[str, object] = {
    "world": "two_rooms",
    "task": "free",
    "task_kwargs": None,
    "backend": "kinematic",
    "physics": None,
    "physics_params": None,
    "bounce_rule": "relative",
    "angles": (45.0, 90.0, 135.0),
    "angle_range": None,
    "noise": None,
    "robot_radius": None,
    "step_length": 1.0,
    "step_mode": "bounce",
    "action_type": "discrete",
    "history": 0,
    "privileged": False,
    "cell_bins": 8,
    "corner_rule": "target_only",
    "n_robots": 1,
    "robot_collisions": "ignore",
    "turn_angles": (),
    "min_sep_cells": 0,
}


@dataclass(frozen=True)
class EnvOptions:
    """Validated, normalised environment arguments (angles in radians)."""

    world: World
    task: object  # as given: a task name or a `Task`, built by the env
    task_kwargs: Mapping | None
    n_robots: int
    backend: str
    bounce_rule: str
    angles: tuple[np.ndarray, ...]  # Φ per robot
    angle_range: tuple[tuple[float, float], ...]  # continuous-action range per robot
    noise: NoiseModel
    robot_radius: float
    step_length: float
    step_mode: str
    action_type: str
    history: int
    privileged: bool
    robot_collisions: str
    cell_bins: int
    corner_rule: str
    min_sep_cells: int = 0
    turn_angles: np.ndarray = field(default_factory=lambda: np.zeros(0))  # turn commands (multi)
    physics: str = "ideal"
    physics_params: PhysicsParams | None = None  # with physics="dynamic"

    @cached_property
    def max_clock(self) -> int:
        """An upper bound on the clock: the longest straight drive, in ticks, plus one — plus,
        with ``physics="dynamic"``, the ticks a bounce spends turning, speeding up and braking
        (`PhysicsParams.overhead_ticks`; the clock observation saturates at 1 beyond it)."""
        ticks = math.ceil(self.world.diameter / self.step_length) + 1
        if self.physics_params is not None:
            ticks += self.physics_params.overhead_ticks(self.step_length)
        return ticks

    @property
    def backend_options(self) -> dict:
        """Extra arguments of the motion backend: the physics of pymunk, the cell backend's
        grid; none otherwise."""
        if self.backend == "pymunk":
            return {"physics": self.physics, "physics_params": self.physics_params}
        if self.backend != "cell":
            return {}
        extra = {"min_sep_cells": self.min_sep_cells} if self.min_sep_cells else {}
        return {"n_bins": self.cell_bins, "corner_rule": self.corner_rule, **extra}

    @property
    def robot_dynamics(self) -> dict:
        """The `BounceDynamics` arguments (with ``world``) of one of the env's robots: the
        motion model that sampled models and particle beliefs simulate."""
        return {"world": self.world, "backend": self.backend, "rule": self.bounce_rule,
                "noise": self.noise, "radius": self.robot_radius,
                "step_length": self.step_length, "backend_options": self.backend_options}


def resolve_world(world: object) -> World:
    """A `World`, a zoo name (see `bounce_gym.worlds.names`) or a path to a map file."""
    if isinstance(world, World):
        return world
    if isinstance(world, os.PathLike) or (isinstance(world, str) and Path(world).suffix):
        path = Path(world)
        if not path.is_file():
            raise ConfigError(f"world: map file {str(path)!r} does not exist")
        return worlds.load(path)
    if isinstance(world, str):
        try:
            return worlds.get(world)
        except InvalidWorldError as exc:  # its message lists the available names
            raise ConfigError(f"world: {exc}") from None
    raise ConfigError(
        f"world: expected a zoo name, a map file path or a World, got {type(world).__name__}"
    )


def _choice(field: str, value: object, allowed: Sequence[str]) -> str:
    if value not in allowed:
        raise ConfigError(f"{field}: expected one of {list(allowed)}, got {value!r}")
    return value  # type: ignore[return-value]


def _angle_set(field: str, values: object, rule: str) -> np.ndarray:
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise ConfigError(f"{field}: expected a list of angles in degrees, got {values!r}")
    degrees = [_number(f"{field}[{k}]", v) for k, v in enumerate(values)]
    radians = np.radians(np.array(degrees, dtype=np.float64))
    check_parameters(rule, radians, field=field)
    if len(set(degrees)) != len(degrees):
        raise ConfigError(f"{field}: angles must be distinct, got {degrees}")
    return radians


def _per_robot(field: str, value: object, n_robots: int) -> list[object]:
    """A shared value, a list with one entry per robot, or a dict robot_<i> -> value."""
    if isinstance(value, Mapping):
        names = [f"robot_{i}" for i in range(n_robots)]
        unknown = sorted(set(value) - set(names))
        missing = [n for n in names if n not in value]
        if unknown or missing:
            raise ConfigError(f"{field}: dict keys must be exactly {names} "
                              f"(unknown {unknown}, missing {missing})")
        return [value[n] for n in names]
    if (isinstance(value, Sequence) and not isinstance(value, str) and value
            and all(isinstance(v, Sequence) and not isinstance(v, str) for v in value)):
        if len(value) != n_robots:
            raise ConfigError(f"{field}: got {len(value)} angle sets for {n_robots} robots")
        return list(value)
    return [value] * n_robots


def _once_each(check, *per_robot: Sequence) -> tuple:
    """``check`` applied to every robot's entries, once per distinct combination of objects: a
    shared value repeats one object, so many robots cost one check."""
    done: dict[tuple[int, ...], object] = {}
    out = []
    for entries in zip(*per_robot, strict=True):
        key = tuple(map(id, entries))
        if key not in done:
            done[key] = check(*entries)
        out.append(done[key])
    return tuple(out)


def _default_range(rule: str, angles: np.ndarray) -> tuple[float, float]:
    if len(angles) > 1:
        return float(angles.min()), float(angles.max())
    return (math.radians(10), math.radians(350)) if rule == "relative" else (
        math.radians(5), math.radians(175))


def _angle_range(field: str, value: object, rule: str, angles: np.ndarray) -> tuple[float, float]:
    if value is None:
        return _default_range(rule, angles)
    if isinstance(value, str) or not isinstance(value, Sequence) or len(value) != 2:
        raise ConfigError(f"{field}: expected (low, high) in degrees, got {value!r}")
    lo, hi = (_number(f"{field}[{k}]", v) for k, v in enumerate(value))
    top = 360.0 if rule == "relative" else 180.0
    if not 0.0 < lo < hi < top:
        raise ConfigError(f"{field}: expected 0 < low < high < {top:g} degrees for rule {rule!r}, "
                          f"got ({lo:g}, {hi:g})")
    return math.radians(lo), math.radians(hi)


def parse_options(kwargs: Mapping, defaults: Mapping | None = None, fixed: Sequence[str] = (),
                  who: str = "the environment") -> EnvOptions:
    """Validate an environment's keyword arguments.

    ``defaults`` replaces some of the defaults of `ARGUMENTS`; the arguments named in ``fixed``
    keep their default and may not be given (the single-robot env fixes ``n_robots`` and the
    other multi-robot arguments). ``who`` names the env in the error for an unknown argument.
    """
    values = keyword_arguments(ARGUMENTS, kwargs, defaults, fixed, who)
    backend = _choice("backend", values["backend"], BACKENDS)
    bounce_rule = _choice("bounce_rule", values["bounce_rule"], sorted(RULES))
    n_robots = integer("n_robots", values["n_robots"], 1, MAX_ROBOTS)
    history = integer("history", values["history"], 0, MAX_HISTORY)
    privileged = values["privileged"]
    if not isinstance(privileged, bool):
        raise ConfigError(f"privileged: expected True or False, got {privileged!r}")
    angle_sets = _once_each(lambda s: _angle_set("angles", s, bounce_rule),
                            _per_robot("angles", values["angles"], n_robots))
    angle_range = values["angle_range"]
    ranges = _once_each(
        lambda r, a: _angle_range("angle_range", r, bounce_rule, a),
        _per_robot("angle_range", angle_range, n_robots) if angle_range is not None
        else [None] * n_robots,
        angle_sets,
    )
    noise_model = make_noise(values["noise"])
    cell_bins = _bins(values["cell_bins"])
    corner_rule = _choice("corner_rule", values["corner_rule"], CORNER_RULES)
    action_type = values["action_type"]
    min_sep_cells = values["min_sep_cells"]
    if backend == "cell":
        _check_cell_backend(bounce_rule, angle_sets, action_type, noise_model, cell_bins)
    elif min_sep_cells != 0:
        raise ConfigError(f"min_sep_cells: only the cell backend has it (continuous robots "
                          f"collide by robot_radius), got {min_sep_cells!r} with backend "
                          f"{backend!r}")
    turns = _turn_angles(values["turn_angles"], action_type,
                         cell_bins if backend == "cell" else None)
    physics, params = _physics(backend, values["physics"], values["physics_params"])
    return EnvOptions(
        world=resolve_world(values["world"]),
        task=values["task"],
        task_kwargs=values["task_kwargs"],
        n_robots=n_robots,
        backend=backend,
        bounce_rule=bounce_rule,
        angles=angle_sets,
        angle_range=ranges,
        noise=noise_model,
        robot_radius=_radius(values["robot_radius"], params),
        step_length=_number("step_length", values["step_length"], minimum=0.0, strict=True),
        step_mode=_choice("step_mode", values["step_mode"], STEP_MODES),
        action_type=_choice("action_type", action_type, ACTION_TYPES),
        history=history,
        privileged=privileged,
        robot_collisions=_choice("robot_collisions", values["robot_collisions"],
                                 ROBOT_COLLISIONS),
        cell_bins=cell_bins,
        corner_rule=corner_rule,
        min_sep_cells=min_sep_cells,  # the cell backend validates it
        turn_angles=turns,
        physics=physics,
        physics_params=params,
    )


def _physics(backend: str, physics: object, params: object) -> tuple[str, PhysicsParams | None]:
    """The motion model and, for ``"dynamic"``, its validated physical parameters."""
    if physics is None:
        physics = "dynamic" if backend == "pymunk" else "ideal"
    physics = _choice("physics", physics, PHYSICS)
    if physics == "dynamic" and backend != "pymunk":
        raise ConfigError(f"physics: backend {backend!r} simulates only 'ideal' motion; "
                          "physics='dynamic' needs backend='pymunk'")
    if physics != "dynamic":
        if params is not None:
            raise ConfigError(f"physics_params: only physics='dynamic' takes physical "
                              f"parameters, got {params!r} with physics={physics!r}")
        return physics, None
    return physics, physics_params(params)


def _radius(value: object, params: PhysicsParams | None) -> float:
    """``robot_radius``: None is a point robot, or the platform's radius under dynamic
    physics, where a body has a size."""
    if value is None:
        return 0.0 if params is None else PLATFORM_RADIUS / params.world_scale
    radius = _number("robot_radius", value, minimum=0.0)
    if params is not None and radius == 0.0:
        raise ConfigError("robot_radius: physics='dynamic' simulates bodies of a size and needs "
                          "robot_radius > 0 (None: the Create 2's 0.17 m / world_scale), got 0")
    return radius


def _turn_angles(value: object, action_type: str, n_bins: int | None) -> np.ndarray:
    """Turn commands (degrees in, radians out): distinct, non-zero, whole bins on the grid."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray):
        raise ConfigError(f"turn_angles: expected a list of angles in degrees, got {value!r}")
    degrees = [_number(f"turn_angles[{k}]", v) for k, v in enumerate(value)]
    if not degrees:
        return np.zeros(0)
    if action_type != "discrete":
        raise ConfigError("turn_angles: turn commands are extra discrete actions; they need "
                          "action_type='discrete'")
    if len(set(degrees)) != len(degrees) or any(d % 360.0 == 0.0 for d in degrees):
        raise ConfigError(f"turn_angles: expected distinct angles that are not multiples of "
                          f"360, got {degrees}")
    if n_bins is not None:
        width = 360.0 / n_bins
        if any(abs(d / width - round(d / width)) > 1e-6 for d in degrees):
            raise ConfigError(f"turn_angles: {degrees} degrees are not whole multiples of the "
                              f"{width:g}° bins of the cell backend")
    return np.radians(np.array(degrees, dtype=np.float64))


def _bins(n_bins: object) -> int:
    if isinstance(n_bins, bool) or not isinstance(n_bins, int | np.integer) or n_bins < 1 \
            or 360 % n_bins:
        raise ConfigError(f"cell_bins: expected a divisor of 360 (e.g. 4, 8, 360), got {n_bins!r}")
    return int(n_bins)


def _check_cell_backend(rule: str, angle_sets, action_type: str, noise: NoiseModel,
                        n_bins: int) -> None:
    """The cell backend steps whole orientation bins with Alam's relative rule."""
    if rule != "relative":
        raise ConfigError(f"bounce_rule: the cell backend supports 'relative' only, got {rule!r}")
    if action_type != "discrete":
        raise ConfigError("action_type: the cell backend needs discrete actions (angles must be "
                          "whole orientation bins)")
    width = 360.0 / n_bins
    for angles in angle_sets:
        steps = np.degrees(angles) / width
        if np.any(np.abs(steps - np.rint(steps)) > 1e-6):
            raise ConfigError(f"angles: {np.degrees(angles).tolist()} degrees are not whole "
                              f"multiples of the {width:g}° bins of the cell backend")
    noise.sample_bins(1, np.random.default_rng(0), math.radians(width))  # raises if not whole
