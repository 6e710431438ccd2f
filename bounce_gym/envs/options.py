"""The keyword arguments of the bouncing-robot environments, declared once: `EnvOptions`.

`BounceEnv`, `GoalNavigationEnv` and the multi-robot envs (`MultiBounceEnv`, `MultiBounceAEC`)
take the fields of `EnvOptions` as keyword arguments — each field's type, default and meaning
are in the model (and in the "Arguments" table of every env page of the docs); an env replaces
a few defaults and leaves out the arguments it does not take (`bounce_gym.envs.arguments`).
Angles enter in **degrees** (this is the configuration edge of the package) and are stored in
radians. An unknown argument raises `TypeError` naming it; every bad value raises `ConfigError`
naming the argument and what is allowed. `bounce_gym.envs.arguments.json_schema` gives an env's JSON Schema.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from functools import cached_property
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    Field,
    SkipValidation,
    ValidationInfo,
    WithJsonSchema,
    field_validator,
    model_validator,
)

from bounce_gym import worlds
from bounce_gym.cells import CORNER_RULES
from bounce_gym.cells.model import check_model_size
from bounce_gym.dynamics.backends.base import ROBOT_COLLISIONS
from bounce_gym.dynamics.noise import NoiseModel, make_noise
from bounce_gym.dynamics.platform import PLATFORM_RADIUS, PhysicsParams, physics_params
from bounce_gym.dynamics.rules import RULES, check_parameters
from bounce_gym.dynamics.simulator import PHYSICS
from bounce_gym.envs.arguments import Accepts, Arguments, Flag, Integer, Real, needs
from bounce_gym.envs.tasks.base import Task
from bounce_gym.errors import ConfigError, InvalidWorldError
from bounce_gym.validate import number
from bounce_gym.worlds import World

Backend = Literal["kinematic", "pymunk", "cell"]
StepMode = Literal["bounce", "tick"]
ActionType = Literal["discrete", "continuous"]
Physics = Literal[PHYSICS]
BACKENDS = Backend.__args__
STEP_MODES = StepMode.__args__
ACTION_TYPES = ActionType.__args__
#: Largest ``history`` (observation length grows by 2 per entry).
MAX_HISTORY = 10_000
#: How large a world may be in metres (its diameter times ``physics_params.world_scale``) under
#: physics='dynamic': from a tabletop to a country (a smaller world leaves the Create 2 no room to
#: brake before the next wall, and its contacts then never settle).
WORLD_METRES = (0.1, 1e7)
#: Largest ``n_robots`` of an env (every robot is a PettingZoo agent with its own dicts; the
#: batched dynamics, `bounce_gym.dynamics.BounceDynamics`, takes more).
MAX_ROBOTS = 10_000

#: a set of angles in degrees; per robot: one set for all, a list of sets or a robot_<i> dict
AngleSets = Sequence[float] | Sequence[Sequence[float]] | Mapping[str, Sequence[float]]
AngleRanges = tuple[float, float] | Sequence[tuple[float, float]] \
    | Mapping[str, tuple[float, float]]


class EnvOptions(Arguments):
    """The arguments of the bouncing-robot envs, validated and normalised (angles in radians,
    one entry per robot; the world, noise model and physical parameters as objects)."""

    world: Annotated[World, Accepts(SkipValidation[str | os.PathLike | World]), WithJsonSchema(
        {"type": "string"}), Field(description=(
            "The map: a zoo name (`bounce_gym.worlds.names()`), the path of a map file, or a "
            "`World`."))] = "two_rooms"
    task: Annotated[SkipValidation[str | Task], WithJsonSchema({"type": "string"}), Field(
        description=(
            "What the robots are scored on: a task name or a `Task` (`bounce_gym.envs.tasks`). "
            "One robot: 'free', 'navigation', 'coverage', 'localization'; several: 'free', "
            "'coverage', 'monitoring'."))] = "free"
    task_kwargs: Annotated[SkipValidation[dict[str, Any] | None], Field(description=(
        "Keyword arguments of the task's class (None: its defaults)."))] = None
    n_robots: Annotated[Integer, Field(ge=1, le=MAX_ROBOTS, description=(
        "Number of robots, each a PettingZoo agent (multi-robot envs)."))] = 1
    backend: Annotated[Backend, Field(description=(
        "The motion model: 'kinematic' (exact and event-driven, continuous poses), 'pymunk' "
        "(a physics engine) or 'cell' (the papers' discrete cell-to-cell model: cells of side "
        "`step_length`, `cell_bins` orientation bins, Alam's relative rule and discrete actions "
        "whose angles are whole bins; one tick is one cell step or one rotation)."))] = \
        "kinematic"
    physics: Annotated[Physics, Accepts(Physics | None), Field(description=(
        "'ideal' (the papers' model: straight drives at `step_length` per tick, turns within "
        "a tick) or 'dynamic' (rigid bodies with mass, motors of bounded acceleration and turn "
        "rate, a bumper, friction and restitution; pymunk only). None: 'dynamic' on pymunk, "
        "'ideal' on the other backends, which have only that."))] = None
    physics_params: Annotated[PhysicsParams | None, Accepts(
        SkipValidation[dict[str, float] | PhysicsParams | None]), Field(
        description=(
            "With physics='dynamic': physical parameters of "
            "`bounce_gym.dynamics.platform.PhysicsParams` to change (SI units, angles in "
            "degrees), e.g. {'cruise_speed': 0.3, 'friction': 0.0}; the rest are an iRobot "
            "Create 2's, with world_scale = 1 metre per world unit."))] = None
    bounce_rule: Annotated[Literal[tuple(sorted(RULES))], Field(description=(
        "How an angle turns the robot at a bump: 'relative' (Alam: relative to the heading), "
        "'fixed', 'specular', 'monotonic', 'nilles_relative' (Nilles: relative to the wall)."
    ))] = "relative"
    angles: Annotated[tuple[np.ndarray, ...], Accepts(SkipValidation[AngleSets]), Field(
        description=(
        "The set of bounce angles Φ, in degrees: distinct, within the rule's range. Several "
        "robots: one set for all, a list with one set per robot, or a {'robot_<i>': set} "
        "dict."))] = (45.0, 90.0, 135.0)
    angle_range: Annotated[tuple[tuple[float, float], ...], Accepts(
        SkipValidation[AngleRanges | None]), Field(description=(
        "(low, high) in degrees, the angles continuous actions map onto: 0 < low < high < 360 "
        "(relative rule) or < 180. None: the smallest and largest of `angles` (10-350 or "
        "5-175 for a single angle). Per robot like `angles`."))] = None
    noise: Annotated[NoiseModel, Accepts(SkipValidation[dict[str, Any] | NoiseModel | None]),
                     WithJsonSchema(
        {"type": ["object", "null"]}), Field(description=(
            "Actuation noise of the bounce angle: None (exact), {'type': 'reliable', 'r': "
            "0.8, 'eps_deg': 5} (the commanded angle with probability r, else off by up to "
            "eps) or {'type': 'interval', 'lo_deg': -5, 'hi_deg': 5} (off by a uniform "
            "amount in the interval)."))] = None
    robot_radius: Annotated[float, Accepts(Real | None), Field(ge=0.0, description=(
        "Robot radius in world units: 0 (a point), or from 1e-4 times the world's diameter to "
        "less than half of it. None: a point, or with physics='dynamic' (where a body has a "
        "size) the Create 2's 0.17 m, i.e. 0.17 / world_scale, within the same bounds."))] = None
    step_length: Annotated[Real, Field(gt=0.0, description=(
        "Distance driven per tick, in world units (1: one cell per tick; the cell size of the "
        "cell model), from 1e-4 times the world's diameter (a drive across the world takes at "
        "most 10^4 ticks) to the diameter; on the cell backend also at most 2^20 cells of the "
        "bounding box and 2^24 cell-model states (cells x cell_bins). With physics='dynamic', "
        "the distance driven in one tick at cruise speed."))] = 1.0
    step_mode: Annotated[StepMode, Field(description=(
        "'bounce': one step is a bump and the drive to the next contact; 'tick': one step is "
        "one tick."))] = "bounce"
    action_type: Annotated[ActionType, Field(description=(
        "'discrete': an action is an index into `angles`; 'continuous': a number in [-1, 1] "
        "mapped onto `angle_range`."))] = "discrete"
    history: Annotated[Integer, Field(ge=0, le=MAX_HISTORY, description=(
        "Number of past (drive ticks, angle) pairs in the observation; at most 10000, far "
        "more bounces than any episode of the papers' experiments has."))] = 0
    privileged: Annotated[Flag, Field(description=(
        "Add the true pose to the observation (an oracle, for comparisons)."))] = False
    agent_id: Annotated[Flag, Field(description=(
        "Several robots: add each robot's index, one-hot (n_robots values), to its observation, "
        "so that one policy shared by the robots can tell them apart."))] = False
    cell_bins: Annotated[Integer, Field(ge=1, le=360, description=(
        "Orientation bins of the env's cell model (a divisor of 360): the cell backend's grid, "
        "and the model the env hands planners on every backend (`env.cell_model()`)."))] = 8
    corner_rule: Annotated[Literal[CORNER_RULES], Field(description=(
        "How the cell model moves diagonally past corners (`bounce_gym.cells.model`)."))] = \
        "target_only"
    robot_collisions: Annotated[Literal[ROBOT_COLLISIONS], Field(description=(
        "'bounce': robots bump into each other and both turn; 'ignore': they pass through "
        "each other."))] = "ignore"
    turn_angles: Annotated[np.ndarray, Accepts(SkipValidation[Sequence[float]]), Field(
        description=(
        "Degrees (counter-clockwise positive): extra discrete actions that turn a robot in "
        "place in one tick, after its angles (parallel multi-robot form only); distinct, not "
        "multiples of 360, whole bins on the cell backend."))] = ()
    min_sep_cells: Annotated[Integer, Field(ge=0, description=(
        "Cell backend: robots within this Chebyshev distance in cells collide (0: only in the "
        "same cell); continuous backends collide by `robot_radius`."))] = 0

    @field_validator("world")
    @classmethod
    def _world(cls, value: object) -> World:
        return resolve_world(value)

    @field_validator("physics")
    @classmethod
    def _physics(cls, value: Physics | None, info: ValidationInfo) -> Physics:
        [backend] = needs(info, "backend")
        if value is None:
            return "dynamic" if backend == "pymunk" else "ideal"
        if value == "dynamic" and backend != "pymunk":
            raise ConfigError(f"physics: backend {backend!r} simulates only 'ideal' motion; "
                              "physics='dynamic' needs backend='pymunk'")
        return value

    @field_validator("physics_params")
    @classmethod
    def _physics_params(cls, value: object, info: ValidationInfo) -> PhysicsParams | None:
        world, physics = needs(info, "world", "physics")
        if physics == "dynamic":
            params = physics_params(value)
            metres = world.diameter * params.world_scale
            if not WORLD_METRES[0] <= metres <= WORLD_METRES[1]:
                low, high = (m / world.diameter for m in WORLD_METRES)
                raise ConfigError(
                    f"physics_params.world_scale: expected metres per world unit in [{low:.3g}, "
                    f"{high:.3g}], so that world {world.name!r} (diameter {world.diameter:.4g} "
                    f"units) measures {WORLD_METRES[0]:g} m to {WORLD_METRES[1]:g} m across, "
                    f"got {params.world_scale!r} ({metres:.3g} m)")
            return params
        if value is not None:
            raise ConfigError(f"physics_params: only physics='dynamic' takes physical "
                              f"parameters, got {value!r} with physics={physics!r}")
        return None

    @field_validator("angles")
    @classmethod
    def _angles(cls, value: object, info: ValidationInfo) -> tuple[np.ndarray, ...]:
        rule, n_robots = needs(info, "bounce_rule", "n_robots")
        return _once_each(lambda s: _angle_set("angles", s, rule),
                          _per_robot("angles", value, n_robots))

    @field_validator("angle_range")
    @classmethod
    def _angle_range(cls, value: object, info: ValidationInfo) -> tuple[tuple[float, float], ...]:
        rule, angles = needs(info, "bounce_rule", "angles")
        given = [None] * len(angles) if value is None else \
            _per_robot("angle_range", value, len(angles))
        return _once_each(lambda r, a: _range("angle_range", r, rule, a), given, angles)

    @field_validator("noise")
    @classmethod
    def _noise(cls, value: object) -> NoiseModel:
        return make_noise(value)

    @field_validator("robot_radius")
    @classmethod
    def _radius(cls, value: float | None, info: ValidationInfo) -> float:
        world, params = needs(info, "world", "physics_params")
        if value is None:
            if params is None:
                return 0.0
            return world.check_length(  # the Create 2 in this world's units
                f"robot_radius (None: the Create 2's {PLATFORM_RADIUS} m / world_scale "
                f"{params.world_scale:g})", PLATFORM_RADIUS / params.world_scale, top=0.5,
                open_top=True)
        # half the diameter: no disk fits (and 1e308 would overflow the packing check)
        world.check_length("robot_radius", value, top=0.5, zero=True, open_top=True)
        if params is not None and value == 0.0:
            raise ConfigError("robot_radius: physics='dynamic' simulates bodies of a size and "
                              "needs robot_radius > 0 (None: the Create 2's 0.17 m / "
                              "world_scale), got 0")
        return value

    @field_validator("step_length")
    @classmethod
    def _step(cls, value: float, info: ValidationInfo) -> float:
        [world] = needs(info, "world")
        return world.check_length("step_length", value)

    @field_validator("cell_bins")
    @classmethod
    def _bins(cls, value: int) -> int:
        if 360 % value:
            raise ConfigError(f"cell_bins: expected a divisor of 360 (e.g. 4, 8, 360), got "
                              f"{value!r}")
        return value

    @field_validator("turn_angles")
    @classmethod
    def _turns(cls, value: object, info: ValidationInfo) -> np.ndarray:
        backend, action_type, bins = needs(info, "backend", "action_type", "cell_bins")
        return _turn_angles(value, action_type, bins if backend == "cell" else None)

    @field_validator("min_sep_cells")
    @classmethod
    def _separation(cls, value: int, info: ValidationInfo) -> int:
        [backend] = needs(info, "backend")
        if value and backend != "cell":
            raise ConfigError(f"min_sep_cells: only the cell backend has it (continuous robots "
                              f"collide by robot_radius), got {value!r} with backend "
                              f"{backend!r}")
        return value

    @model_validator(mode="after")
    def _agent_id(self) -> EnvOptions:
        if self.agent_id and self.n_robots < 2:
            raise ConfigError("agent_id: a lone robot has no other robot to be told apart from "
                              "(it needs n_robots >= 2)")
        return self

    @model_validator(mode="after")
    def _cell_backend(self) -> EnvOptions:
        """The cell backend steps whole orientation bins with Alam's relative rule."""
        if self.backend != "cell":
            return self
        if self.bounce_rule != "relative":
            raise ConfigError(f"bounce_rule: the cell backend supports 'relative' only, got "
                              f"{self.bounce_rule!r}")
        if self.action_type != "discrete":
            raise ConfigError("action_type: the cell backend needs discrete actions (angles "
                              "must be whole orientation bins)")
        check_model_size(self.world, self.step_length, self.cell_bins, "step_length")
        width = 360.0 / self.cell_bins
        for angles in self.angles:
            steps = np.degrees(angles) / width
            if np.any(np.abs(steps - np.rint(steps)) > 1e-6):
                raise ConfigError(f"angles: {np.degrees(angles).tolist()} degrees are not "
                                  f"whole multiples of the {width:g}° bins of the cell backend")
        self.noise.sample_bins(1, np.random.default_rng(0), math.radians(width))  # if not whole
        return self

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


def _angle_set(field: str, values: object, rule: str) -> np.ndarray:
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise ConfigError(f"{field}: expected a list of angles in degrees, got {values!r}")
    degrees = [number(f"{field}[{k}]", v) for k, v in enumerate(values)]
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


def _range(field: str, value: object, rule: str, angles: np.ndarray) -> tuple[float, float]:
    if value is None:
        return _default_range(rule, angles)
    if isinstance(value, str) or not isinstance(value, Sequence) or len(value) != 2:
        raise ConfigError(f"{field}: expected (low, high) in degrees, got {value!r}")
    lo, hi = (number(f"{field}[{k}]", v) for k, v in enumerate(value))
    top = 360.0 if rule == "relative" else 180.0
    if not 0.0 < lo < hi < top:
        raise ConfigError(f"{field}: expected 0 < low < high < {top:g} degrees for rule {rule!r}, "
                          f"got ({lo:g}, {hi:g})")
    return math.radians(lo), math.radians(hi)


def _turn_angles(value: object, action_type: str, n_bins: int | None) -> np.ndarray:
    """Turn commands (degrees in, radians out): distinct, non-zero, whole bins on the grid."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray):
        raise ConfigError(f"turn_angles: expected a list of angles in degrees, got {value!r}")
    degrees = [number(f"turn_angles[{k}]", v) for k, v in enumerate(value)]
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
