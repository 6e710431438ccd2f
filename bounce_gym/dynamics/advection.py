"""Continuous drifters: many point masses carried by a `FlowField`, all at once.

Each step of ``dt`` seconds (`Drifters.step`):

1. **advection**: one classical RK4 step through the field, bilinear in space and linear in
   time (`bounce_gym.flows.integrate.rk4_step`; stages at t, t + dt/2, t + dt), each drifter in
   its own layer;
2. **diffusion** (optional): a Brownian displacement of standard deviation sqrt(2 K dt) metres
   per axis (K = ``diffusivity`` in m^2/s, Euler-Maruyama), drawn from the drifters' own seeded
   generator;
3. **land rule** for a drifter whose new position is on land or off the grid (a point is in the
   cell of its nearest node; docs/choices/drifters.md, "Drifters at the coast"):
   ``"stay"`` keeps it where it was; ``"slide"`` keeps the part of the move along the coast:
   the move along x alone if that ends in water, else the move along y alone, else it stays.

A profiling drifter changes layer instantly with `apply_actions` (the actions of
`bounce_gym.cells.drifter`: 0 drift, 1 up, 2 down), legal only where the new layer exists and
the drifter's cell is water in it (`legal_actions`). The clock is shared by all drifters.
"""

from __future__ import annotations

import numpy as np

from bounce_gym import validate
from bounce_gym.cells.drifter import ACTIONS, DOWN, DRIFT, UP
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.flows import METRES_PER_DEGREE, FlowField
from bounce_gym.flows.integrate import rk4_step

__all__ = ["LAND_RULES", "Drifters"]

#: What a drifter whose step ends on land (or off the grid) does.
LAND_RULES = ("stay", "slide")


class Drifters:
    """N drifters in a flow field.

    Args:
        field: the flow.
        x: (N,) start x positions in the field's coordinates; each (x, y) must be in water.
        y: (N,) start y positions.
        layer: (N,) or scalar start layers.
        t: start time in seconds (default: the field's first snapshot, or 0 if static).
        land_rule: ``"stay"`` or ``"slide"`` (module docstring).
        diffusivity: K >= 0 in m^2/s.
        rng: a `numpy.random.Generator` or an int seed for the diffusion (default seed 0).
        outside: ``"error"`` or ``"hold"``: sampling after the field's last snapshot.

    Attributes:
        x, y: (N,) float64 positions; layer: (N,) int64; t: the clock in seconds.
    """

    def __init__(self, field: FlowField, x, y, layer=0, *, t: float | None = None,
                 land_rule: str = "stay", diffusivity: float = 0.0, rng=0,
                 outside: str = "error") -> None:
        if not isinstance(field, FlowField):
            raise ConfigError(f"field: expected a FlowField, got {type(field).__name__}")
        if land_rule not in LAND_RULES:
            raise ConfigError(f"land_rule: expected one of {LAND_RULES}, got {land_rule!r}")
        self.field, self.land_rule, self.outside = field, land_rule, outside
        self.diffusivity = validate.number("diffusivity", diffusivity, minimum=0.0)
        self.rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(
            validate.integer("rng", rng, 0))
        x = validate.numbers("x", x)
        y = validate.numbers("y", y)
        if x.ndim != 1 or x.shape != y.shape:
            raise ConfigError(f"x, y: expected two 1-D arrays of one length, got {x.shape} and "
                              f"{y.shape}")
        layer = np.broadcast_to(np.asarray(layer), x.shape)
        if layer.dtype.kind not in "iu" or np.any(layer < 0) or np.any(layer >= field.n_layers):
            raise ConfigError(f"layer: expected integers in [0, {field.n_layers - 1}]")
        self.x, self.y, self.layer = x.copy(), y.copy(), layer.astype(np.int64)
        dry = ~field.water_at(self.x, self.y, self.layer)
        if dry.any():
            k = int(np.flatnonzero(dry)[0])
            raise ConfigError(f"x, y: drifter {k} at ({x[k]}, {y[k]}) in layer {layer[k]} is "
                              "not in water")
        if t is None:
            t = 0.0 if field.time is None else float(field.time[0])
        self.t = validate.number("t", t)

    @property
    def n(self) -> int:
        return len(self.x)

    def step(self, dt: float) -> np.ndarray:
        """Advance every drifter by ``dt`` seconds; returns the (N,) bool mask of drifters the
        land rule held back."""
        dt = validate.number("dt", dt, minimum=0.0, strict=True)
        t = None if self.field.time is None else self.t
        nx, ny = rk4_step(self.field, self.x, self.y, self.layer, dt, t, outside=self.outside)
        if self.diffusivity > 0:
            sigma = np.sqrt(2.0 * self.diffusivity * dt)
            ex, ey = sigma * self.rng.standard_normal((2, self.n))
            if self.field.crs == "lonlat":
                ex = ex / (METRES_PER_DEGREE * np.cos(np.radians(self.y)))
                ey = ey / METRES_PER_DEGREE
            nx, ny = nx + ex, ny + ey
        blocked = ~self.field.water_at(nx, ny, self.layer)
        if blocked.any():
            nx, ny = self._land(nx, ny, blocked)
        self.x, self.y = nx, ny
        self.t += dt
        return blocked

    def run(self, dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """``n_steps`` steps; returns the trajectories x, y, each (n_steps + 1, N), the start
        included."""
        n_steps = validate.integer("n_steps", n_steps, 0)
        xs, ys = [self.x.copy()], [self.y.copy()]
        for _ in range(n_steps):
            self.step(dt)
            xs.append(self.x.copy())
            ys.append(self.y.copy())
        return np.stack(xs), np.stack(ys)

    def legal_actions(self) -> np.ndarray:
        """(N, 3) bool: drift always; up/down where that layer exists and is water here."""
        legal = np.ones((self.n, 3), dtype=bool)
        for action, delta in ((UP, -1), (DOWN, 1)):
            target = self.layer + delta
            ok = (target >= 0) & (target < self.field.n_layers)
            legal[:, action] = ok
            legal[ok, action] = self.field.water_at(self.x[ok], self.y[ok], target[ok])
        return legal

    def apply_actions(self, actions) -> None:
        """Move drifters up (1) or down (2) a layer, or leave them (0). Raises `ActionError` for
        an unknown or illegal action."""
        actions = np.asarray(actions)
        if actions.shape != (self.n,) or actions.dtype.kind not in "iu" or np.any(
                (actions < 0) | (actions > 2)):
            raise ActionError(f"actions: expected ({self.n},) integers 0 (drift), 1 (up), "
                              "2 (down)")
        legal = self.legal_actions()[np.arange(self.n), actions]
        if not legal.all():
            k = int(np.flatnonzero(~legal)[0])
            raise ActionError(f"actions: {ACTIONS[int(actions[k])]} is illegal for drifter {k} "
                              f"in layer {int(self.layer[k])}")
        self.layer = self.layer + np.where(actions == UP, -1, np.where(actions == DRIFT, 0, 1))

    def _land(self, nx, ny, blocked) -> tuple[np.ndarray, np.ndarray]:
        nx, ny = nx.copy(), ny.copy()
        b = np.flatnonzero(blocked)
        if self.land_rule == "stay":
            nx[b], ny[b] = self.x[b], self.y[b]
            return nx, ny
        lay = self.layer[b]
        along_x = self.field.water_at(nx[b], self.y[b], lay)
        along_y = ~along_x & self.field.water_at(self.x[b], ny[b], lay)
        neither = ~along_x & ~along_y
        ny[b[along_x]] = self.y[b[along_x]]
        nx[b[along_y]] = self.x[b[along_y]]
        nx[b[neither]], ny[b[neither]] = self.x[b[neither]], self.y[b[neither]]
        return nx, ny
