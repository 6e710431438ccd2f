"""Time-optimal turn-in-place profiles for a controller with a fixed period.

A robot at rest turns by an angle Δ. Its controller runs every ``period`` h seconds; at each
instant it sets the angular velocity the motors reach by the next instant, changing it by at most
α h (the turn acceleration α) and never beyond the turn rate W. Between instants the engine moves
the robot with the velocity it had at the start of the step (pymunk integrates positions before
velocities), so a profile ω_1, …, ω_{n-1} (ω_0 = ω_n = 0) turns by h (ω_1 + … + ω_{n-1}) and ends
at rest after n periods.

`turn_profile` returns the shortest such profile that turns by exactly Δ: the fastest one —
ω_j = min(j α h, W, (n − j) α h), a trapezoid (a triangle when W is not reached) — for the fewest
periods n that reach Δ, scaled down to land on Δ. Scaling keeps every step within α h and W, and
the turn takes at most one period more than the continuous optimum (2 √(Δ/α), or Δ/W + W/α).
"""

from __future__ import annotations

import math

import numpy as np


def turn_profile(delta: float, rate: float, accel: float, period: float) -> tuple[float, ...]:
    """Angular velocities ω_1 … ω_{n-1} (rad/s, the sign of ``delta``) of the shortest profile
    turning a resting robot by ``delta`` radians, then coming to rest. ``rate`` (rad/s) and
    ``accel`` (rad/s²) may be ``inf``; ``period`` is finite and positive. Empty for ``delta = 0``.
    """
    size = abs(delta)
    if size == 0.0:
        return ()
    sign = math.copysign(1.0, delta)
    step = accel * period  # the largest change per period
    if math.isinf(step) and math.isinf(rate):
        return (sign * size / period,)  # one period at whatever speed the angle needs
    if math.isinf(step):  # instant changes: flat at the turn rate
        n = math.ceil(size / (rate * period)) + 1
        ramp = np.full(n - 1, rate)
    else:
        n = _periods(size, rate, step, period)
        j = np.arange(1, n)
        ramp = np.minimum(np.minimum(j * step, (n - j) * step), rate)
    scale = size / (period * float(ramp.sum()))
    return tuple((sign * scale * ramp).tolist())


def _periods(size: float, rate: float, step: float, period: float) -> int:
    """The fewest periods n whose fastest profile turns by at least ``size``."""
    accel = step / period
    if math.isinf(rate) or size <= rate * rate / accel:
        optimum = 2.0 * math.sqrt(size / accel)
    else:
        optimum = size / rate + rate / accel
    n = max(2, int(optimum / period))
    while _area(n, rate, step, period) < size:
        n += 1
    return n


def _area(n: int, rate: float, step: float, period: float) -> float:
    """Angle turned by the fastest profile of n periods."""
    j = np.arange(1, n)
    return period * float(np.minimum(np.minimum(j * step, (n - j) * step), rate).sum())
