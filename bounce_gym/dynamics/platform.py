"""The physical robot of ``physics="dynamic"``: an iRobot Create 2, in SI units, and its options.

The defaults describe the iRobot Create 2 (a Roomba 600 without the vacuum), the platform of the
hardware experiments of Alam, Bobadilla & Shell 2017 (§VI) and Alam & Bobadilla 2020 (§5). Sources:

* **Diameter 0.34 m** (radius `PLATFORM_RADIUS` = 0.17 m): the Roomba 600's round body, drawn in
  "Roomba Physical Dimensions" of iRobot, *Create 2 Open Interface (OI) Specification based on the
  Roomba 600* (2015, revised 2018); every Roomba is a disc of about 34 cm (Wikipedia, "Roomba").
* **Mass 3.6 kg**: iRobot's Create 2 product listing (3.58 kg, 7.9 lb).
* **Wheel base 0.235 m** and **maximum wheel speed 0.5 m/s**: the OI specification (the Drive
  commands take wheel speeds in −500 … 500 mm/s; the wheels are 235 mm apart).
* **Maximum turn rate** 2 × 0.5 / 0.235 = 4.26 rad/s (244°/s): both wheels at full speed in
  opposite directions (a differential drive turning in place).
* **Cruise speed 0.25 m/s** (chosen): half the commandable maximum, the middle of the 100–300
  mm/s that Create 2 examples drive at, which leaves the controller headroom to hold the speed
  when pushed. The papers' robots drive "at a fixed speed" without giving it.
* **Turn rate 122°/s** (chosen): the wheels turning in place at the cruise speed,
  2 × 0.25 / 0.235 rad/s, so that the motors run at one speed setting throughout; the papers'
  robots turn "by commanding a constant angular velocity for a fixed period" (Alam, Bobadilla &
  Shell 2018, §II).
* **Maximum acceleration 0.5 m/s²** (**assumed**: the OI specification publishes none): reaching
  the cruise speed in 0.5 s over 6 cm, as the Create visibly does. Each wheel accelerates at
  most this much, so turning accelerates at up to 2 × 0.5 / 0.235 = 4.26 rad/s².
* **Bumper arc 180°**: the bumper covers the front half of the body, with a left and a right
  switch (OI specification, sensor packet 7 "Bumps and Wheel Drops"; Wikipedia, "Roomba").
* **Restitution 0** (assumed): the sprung bumper absorbs the impact; the robot does not rebound.
* **Friction 0.3** (assumed): a plastic bumper on painted walls and on another bumper, a common
  textbook value for plastic on wood or paint.
* **Stall: below half the commanded speed for 1 s** (assumed): the Create 2 reports a wheel
  overcurrent (OI specification, sensor packet 14 "Wheel Overcurrents") when a wheel's motor
  draws too much current — when it pushes at full force and barely turns — without publishing
  the threshold or how long it takes to trip. A driving robot in contact whose speed along its
  heading (the speed its wheels roll at) stays below ``stall_fraction`` of the commanded speed
  for ``stall_time`` seconds stalls, which counts as a bump (see
  `bounce_gym.dynamics.backends.pymunk_dynamic`).
* **Control period 0.25 s** (chosen): the controller updates its wheel speed set points four
  times a second, each time to the mean of the time-optimal speed profile over the coming
  period, so that the robot is where a continuously accelerating one would be at every update
  (`bounce_gym.dynamics.profiles`); within a period it moves at that mean. The bumper is a
  reflex and acts at once. A shorter period follows the ramps more finely and costs more engine
  steps per bounce (the OI streams sensor data every 15 ms).

Lengths in the world are in *world units*; ``world_scale`` says how many metres one unit is
(default 1: the lab maps' 1-unit cells are 1 m squares). `PhysicsParams` holds the SI values as
given; `bounce_gym.dynamics.backends.pymunk_dynamic` converts them to world units.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

from bounce_gym.dynamics.profiles import Turn
from bounce_gym.errors import ConfigError
from bounce_gym.validate import integer, number

#: Radius of the Create 2's body in metres (diameter 0.34 m).
PLATFORM_RADIUS = 0.17
#: Distance between the Create 2's wheels in metres.
WHEEL_BASE = 0.235
#: Default cruise speed in m/s.
CRUISE_SPEED = 0.25


@dataclass(frozen=True)
class PhysicsParams:
    """Physical parameters of ``physics="dynamic"``, SI units (angles in degrees), Create 2 defaults.

    Attributes:
        world_scale: metres per world unit.
        mass: kg; the moment of inertia is that of a uniform disk, m r² / 2.
        wheel_base: m, distance between the two drive wheels.
        max_speed: m/s, the fastest a wheel turns (bounds ``cruise_speed`` and ``turn_rate``).
        cruise_speed: m/s, the speed the robot drives at.
        max_acceleration: m/s², the most a wheel speeds up or slows down per second; also the
            traction: the motors push the body towards the commanded velocity with at most
            mass × max_acceleration. ``inf``: velocities change within one engine step.
        turn_rate: degrees/s, the turn rate of a turn in place (at most
            2 max_speed / wheel_base). ``inf`` with ``max_speed = inf``: turns take one period.
        bumper_arc: degrees, the front arc whose contacts press the bumper (centred on the
            heading).
        restitution: coefficient of restitution of every contact, in [0, 1].
        friction: Coulomb friction coefficient of every contact.
        stall_fraction: a driving robot in contact stalls (a bump) when its speed along its
            heading stays below this fraction of the commanded speed, in (0, 1] ...
        stall_time: s, ... for this long.
        control_period: s, how often the controller sets the wheel speeds (the time resolution
            of speeding up, braking and turning).
        iterations: iterations of pymunk's contact solver per engine step (default 100, ten
            times pymunk's: a disk squeezed into a narrow wedge — two walls at a sharp angle,
            nearly opposite contact normals — creeps in with fewer).
    """

    world_scale: float = 1.0
    mass: float = 3.6
    wheel_base: float = WHEEL_BASE
    max_speed: float = 0.5
    cruise_speed: float = CRUISE_SPEED
    max_acceleration: float = 0.5
    turn_rate: float = math.degrees(2 * CRUISE_SPEED / WHEEL_BASE)
    bumper_arc: float = 180.0
    restitution: float = 0.0
    friction: float = 0.3
    stall_fraction: float = 0.5
    stall_time: float = 1.0
    control_period: float = 0.25
    iterations: int = 100

    @property
    def turn_acceleration(self) -> float:
        """rad/s²: both wheels accelerating at ``max_acceleration`` in opposite directions."""
        return 2.0 * self.max_acceleration / self.wheel_base

    @property
    def max_turn_rate(self) -> float:
        """rad/s: both wheels at ``max_speed`` in opposite directions."""
        return 2.0 * self.max_speed / self.wheel_base

    def tick_seconds(self, step_length: float) -> float:
        """Duration of a tick: the time to drive ``step_length`` world units at cruise speed."""
        return step_length * self.world_scale / self.cruise_speed

    def overhead_ticks(self, step_length: float) -> int:
        """An upper bound on the ticks a bounce spends beyond driving at cruise speed: a full
        turn (2π, at the turn rate and acceleration), the time lost speeding up and braking,
        and a control period for each, rounded up, plus one."""
        turn = Turn(2 * math.pi, math.radians(self.turn_rate), self.turn_acceleration,
                    self.control_period).duration
        speed = 1.5 * self.cruise_speed / self.max_acceleration
        seconds = turn + speed + 3 * self.control_period
        return math.ceil(seconds / self.tick_seconds(step_length)) + 1


#: Parameters that may be ``inf`` (the limit of an ideal robot), with their lower bounds.
_POSITIVE = ("world_scale", "mass", "wheel_base", "control_period", "stall_time")
_MAY_BE_INFINITE = ("max_speed", "max_acceleration", "turn_rate")


def physics_params(options: object, field: str = "physics_params") -> PhysicsParams:
    """`PhysicsParams` from a mapping of the names above to values (missing names keep the Create 2
    defaults; a `PhysicsParams` is returned as it is). Every value is checked: a `ConfigError`
    names the field and the allowed range."""
    if isinstance(options, PhysicsParams):
        return options
    if options is None:
        options = {}
    if not isinstance(options, Mapping):
        raise ConfigError(f"{field}: expected a mapping of physical parameters, got {options!r}")
    names = [f.name for f in fields(PhysicsParams)]
    unknown = sorted(str(k) for k in options if k not in names)
    if unknown:
        raise ConfigError(f"{field}: unknown parameters {unknown}; allowed are {names}")
    values: dict[str, float | int] = {}
    for name in _POSITIVE:
        if name in options:
            values[name] = number(f"{field}.{name}", options[name], minimum=0.0, strict=True)
    for name in _MAY_BE_INFINITE:
        if name in options:
            values[name] = _positive_or_inf(f"{field}.{name}", options[name])
    for name in ("cruise_speed", "friction", "restitution", "bumper_arc"):
        if name in options:
            values[name] = number(f"{field}.{name}", options[name], minimum=0.0,
                                  strict=name in ("cruise_speed", "bumper_arc"))
    if "stall_fraction" in options:
        values["stall_fraction"] = number(f"{field}.stall_fraction", options["stall_fraction"],
                                          minimum=0.0, maximum=1.0, strict=True)
    if "iterations" in options:
        values["iterations"] = integer(f"{field}.iterations", options["iterations"], 1, 1000)
    params = PhysicsParams(**values)
    _check_ranges(params, field)
    return params


def _positive_or_inf(field: str, value: object) -> float:
    if isinstance(value, float | int) and not isinstance(value, bool) and value == math.inf:
        return math.inf
    return number(field, value, minimum=0.0, strict=True)


def _check_ranges(p: PhysicsParams, field: str) -> None:
    """The bounds between parameters."""
    if p.cruise_speed > p.max_speed:
        raise ConfigError(f"{field}.cruise_speed: expected at most max_speed = {p.max_speed:g} "
                          f"m/s, got {p.cruise_speed:g}")
    limit = math.degrees(p.max_turn_rate)
    if p.turn_rate > limit:
        raise ConfigError(f"{field}.turn_rate: expected at most 2 max_speed / wheel_base = "
                          f"{limit:g} degrees/s, got {p.turn_rate:g}")
    if p.restitution > 1.0:
        raise ConfigError(f"{field}.restitution: expected a number in [0, 1], got "
                          f"{p.restitution:g}")
    if p.bumper_arc > 360.0:
        raise ConfigError(f"{field}.bumper_arc: expected degrees in (0, 360], got "
                          f"{p.bumper_arc:g}")
