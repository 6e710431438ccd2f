"""Time-optimal motion profiles of a robot with a speed limit and an acceleration limit.

The motor controller of ``physics="dynamic"`` (`bounce_gym.dynamics.backends.pymunk_dynamic`)
commands its wheels at control instants, a period h apart. Between two instants it holds one
velocity: the **mean** of the continuous profile over the period, so that the robot is exactly
where the continuous profile would have it at every instant, however long the period. The three
profiles, each with ``mean(u, v, span)`` over the times u < v since its start and
``duration``:

* `SpeedUp` — from rest to the cruise speed at constant acceleration, then cruising;
* `SlowDown` — from a speed to rest at constant deceleration;
* `Turn` — a rest-to-rest turn in place by an angle: the turn rate rises at the turn
  acceleration to the turn rate limit, holds it and falls again (a triangle when the limit is not
  reached) — the time-optimal profile, which lasts Δ/W + W/α (or 2 √(Δ/α)).

Infinite limits are allowed (the limit of an ideal robot): an infinite acceleration reaches its
speed at once; a turn with an infinite rate and acceleration lasts ``period`` (one period).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class SpeedUp:
    """Speed min(a t, top) from rest: accelerate at ``accel`` to ``top``, then hold it."""

    top: float
    accel: float

    @property
    def duration(self) -> float:
        """When the top speed is reached."""
        return self.top / self.accel

    def distance(self, t: float) -> float:
        """Distance covered after t seconds."""
        reach = self.duration
        if t <= reach:
            return 0.5 * self.accel * t * t
        return 0.5 * self.top * reach + self.top * (t - reach)

    def mean(self, u: float, v: float, span: float) -> float:
        """The mean speed over [u, v], as the distance covered divided by ``span`` (the
        length of the step as the caller computes it, so that speed x span is the distance)."""
        if u >= self.duration:
            return self.top
        return (self.distance(v) - self.distance(u)) / span


@dataclass(frozen=True)
class SlowDown:
    """Speed max(start − a t, 0): decelerate at ``accel`` from ``start`` to rest."""

    start: float
    accel: float

    @property
    def duration(self) -> float:
        return self.start / self.accel

    def distance(self, t: float) -> float:
        stop = self.duration
        if t >= stop:
            return 0.5 * self.start * stop
        return self.start * t - 0.5 * self.accel * t * t

    def mean(self, u: float, v: float, span: float) -> float:
        """The mean speed over [u, v]: distance covered / ``span`` (see `SpeedUp.mean`)."""
        if u >= self.duration:
            return 0.0
        return (self.distance(v) - self.distance(u)) / span


class Turn:
    """The time-optimal rest-to-rest turn by ``delta`` radians (sign = direction) with turn
    rate at most ``rate`` and turn acceleration at most ``accel``; ``period`` is its duration
    when both are infinite.

    Attributes:
        peak: the highest turn rate reached (the limit, or the tip of the triangle).
        ramp: seconds spent speeding up (and again slowing down).
        duration: seconds from rest to rest.
    """

    __slots__ = ("delta", "rate", "accel", "peak", "ramp", "duration")

    def __init__(self, delta: float, rate: float, accel: float, period: float) -> None:
        self.delta, self.rate, self.accel = delta, rate, accel
        self.peak = min(rate, math.sqrt(accel * abs(delta)))
        if math.isinf(self.peak):
            self.ramp, self.duration = 0.0, period
        else:
            self.ramp = self.peak / accel
            self.duration = abs(delta) / self.peak + self.ramp

    def __getstate__(self) -> tuple:
        return tuple(getattr(self, k) for k in self.__slots__)

    def __setstate__(self, state: tuple) -> None:
        for k, v in zip(self.__slots__, state, strict=True):
            setattr(self, k, v)

    def angle(self, t: float) -> float:
        """Signed angle turned after t seconds."""
        size, end = abs(self.delta), self.duration
        if t >= end:
            turned = size
        elif math.isinf(self.peak):
            turned = size * t / end
        else:
            ramp, peak = self.ramp, self.peak
            if t <= ramp:
                turned = 0.5 * self.accel * t * t
            elif t <= end - ramp:
                turned = 0.5 * peak * ramp + peak * (t - ramp)
            else:
                turned = size - 0.5 * self.accel * (end - t) ** 2
        return math.copysign(turned, self.delta)

    def mean(self, u: float, v: float, span: float) -> float:
        """The mean turn rate over [u, v]: angle turned / ``span`` (see `SpeedUp.mean`); the
        angles of consecutive periods add up to ``delta`` exactly, up to rounding."""
        if u >= self.duration:
            return 0.0
        return (self.angle(v) - self.angle(u)) / span

    def plateau_end(self) -> float:
        """When the turn rate starts falling (the start of the last ramp)."""
        return self.duration - self.ramp
