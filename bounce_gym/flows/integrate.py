"""Flow lines: one classical Runge-Kutta (RK4) step of many points through a `FlowField`.

Positions are in the field's coordinates; velocities (m/s) are turned into coordinate rates at
each stage's own position (for ``"lonlat"``: degrees per second, using `METRES_PER_DEGREE` and
the cosine of the stage's latitude, as OceanParcels does). Stages sample the field at
t, t + dt/2, t + dt, or all at t with ``frozen=True`` (a flow line of one snapshot, as the cell
map of a snapshot needs).
"""

from __future__ import annotations

import numpy as np

from bounce_gym.errors import InvalidFlowError
from bounce_gym.flows.field import METRES_PER_DEGREE, FlowField

__all__ = ["coordinate_rates", "rk4_step"]


def coordinate_rates(field: FlowField, x, y, layer, t, outside: str = "error"
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(dx/dt, dy/dt) in coordinate units per second at points (x, y) of ``layer``."""
    u, v = field.velocity(x, y, layer, t, outside)
    if field.crs == "lonlat":
        u = u / (METRES_PER_DEGREE * np.cos(np.radians(y)))
        v = v / METRES_PER_DEGREE
    return u, v


def rk4_step(field: FlowField, x, y, layer, dt, t: float | None = None, *, frozen: bool = False,
             outside: str = "error") -> tuple[np.ndarray, np.ndarray]:
    """Positions after one RK4 step of ``dt`` seconds from time ``t`` (None for a static
    field). ``dt`` is a scalar, or one value per point when ``frozen`` (every stage at t)."""
    dt = np.asarray(dt, dtype=np.float64)
    if frozen or t is None:
        t_half = t_end = t
    elif dt.ndim:
        raise InvalidFlowError("dt: one time step for all points unless frozen=True")
    else:
        t_half, t_end = t + 0.5 * float(dt), t + float(dt)
    k1x, k1y = coordinate_rates(field, x, y, layer, t, outside)
    k2x, k2y = coordinate_rates(field, x + 0.5 * dt * k1x, y + 0.5 * dt * k1y, layer, t_half,
                                outside)
    k3x, k3y = coordinate_rates(field, x + 0.5 * dt * k2x, y + 0.5 * dt * k2y, layer, t_half,
                                outside)
    k4x, k4y = coordinate_rates(field, x + dt * k3x, y + dt * k3y, layer, t_end, outside)
    return (x + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            y + dt / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y))
