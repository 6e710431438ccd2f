"""The flow zoo: seeded, procedural stand-ins for ocean-model output, ``get_flow(name, **kwargs)``.

The thesis' fields come from ROMS predictions for the Southern California Bight (Alam 2018,
§5.4.1), which are not distributed; these synthetic fields reproduce the structures ch. 5 works
with, and go through the same code as a user's file (tests write and read each one as NetCDF).

* ``two_sink``: the 21 x 29 basin of ch. 5 in metres (1 km cells, y = north). Land: the eastern
  strip ``i >= 26`` and the north-east corner ``j >= 17, i >= 20``, leaving 522 water cells. The
  flow is ``F = grad(g1 + g2) + swirl * k x grad(g1)`` with Gaussian wells
  ``g_k = exp(-|p - c_k|^2 / 36)`` (p in grid units) centred at c1 = (i 10, j 13) and
  c2 = (i 20, j 7), scaled so that the fastest cell moves at ``speed``; the swirl turns the
  flow clockwise around c1. Under the unit-step GCM it has two persistent groups and three
  transient groups (one per domicile set), the structure of thesis Fig. 5.7.
* ``scb_like``: the thesis' region (33.30-33.70 N, 118.26-117.70 W) on a 0.02 degree grid
  (21 x 29, lon/lat), a NW-SE coastline in the north-east with a shelf that makes deeper layers
  lose coastal cells, an optional island, an equatorward along-shore current, a cyclonic and an
  anticyclonic eddy (seeded positions), a convergence band, and an M2 tide (12.42 h) plus a
  diurnal (K1, 23.93 h) tidal current with seeded phases, sampled hourly for a day. Layers at
  0, 5 and 10 m turn by -20 degrees per layer and decay as exp(-z / 20 m) (Ekman-like).
* ``double_gyre``: Shadden, Lekien & Marsden (2005), A = 0.1, eps = 0.25, omega = 2 pi / 10 on
  [0, 2] x [0, 1] (metres, seconds), sampled every 0.5 s for two periods.
* ``solid_body``: rotation about the basin centre (one turn per ``period`` seconds).
* ``uniform``: the same velocity everywhere.

``solid_body`` and ``uniform`` use the ``two_sink`` basin by default (``basin="open"``: no land).
Every field can be stacked into layers with `ekman_layers` (``n_layers``).
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from bounce_gym import validate
from bounce_gym.errors import ConfigError, InvalidFlowError
from bounce_gym.flows.field import FlowField

__all__ = ["BASINS", "double_gyre", "ekman_layers", "flow_names", "get_flow", "scb_like", "solid_body",
           "two_sink", "two_sink_land", "uniform"]

#: Land layouts of ``solid_body`` and ``uniform``.
BASINS = ("two_sink", "open")
_TWO_SINK_SHAPE = (21, 29)
_M2_HOURS = 12.42
_K1_HOURS = 23.93


def flow_names() -> list[str]:
    """Sorted names of the zoo fields."""
    return sorted(_FIELDS)


def get_flow(name: str, **kwargs) -> FlowField:
    """The zoo field ``name`` built with ``kwargs`` (see each builder's signature).

    Raises:
        InvalidFlowError: unknown name (the message lists them) or unknown argument.
        ConfigError: an argument of the wrong type or range.
    """
    if not isinstance(name, str) or name not in _FIELDS:
        raise InvalidFlowError(f"unknown flow {name!r}; available: {', '.join(flow_names())}")
    builder = _FIELDS[name]
    allowed = list(inspect.signature(builder).parameters)
    for key in kwargs:
        if key not in allowed:
            raise InvalidFlowError(f"{name}: unknown argument {key!r}; allowed: "
                                   f"{', '.join(allowed)}")
    return builder(**kwargs)


# -- stacking layers --------------------------------------------------------------------------
def ekman_layers(u: np.ndarray, v: np.ndarray, depths, turn_deg: float = -20.0,
                 e_folding: float = 20.0) -> tuple[np.ndarray, np.ndarray]:
    """Stack a surface field into layers: layer k is the surface flow turned by
    ``k * turn_deg`` degrees (negative = clockwise) and scaled by ``exp(-depth_k / e_folding)``.
    ``u``, ``v``: (..., Ny, Nx); returns (L, ..., Ny, Nx)."""
    depths = np.asarray(depths, np.float64)
    us, vs = [], []
    for k, z in enumerate(depths):
        a = math.radians(turn_deg * k)
        s = math.exp(-z / e_folding)
        us.append(s * (math.cos(a) * u - math.sin(a) * v))
        vs.append(s * (math.sin(a) * u + math.cos(a) * v))
    return np.stack(us), np.stack(vs)


def _layer_depths(n_layers: int, spacing: float = 5.0) -> np.ndarray:
    validate.integer("n_layers", n_layers, 1, 100)
    return spacing * np.arange(n_layers, dtype=np.float64)


# -- two_sink ---------------------------------------------------------------------------------
def two_sink_land() -> np.ndarray:
    """(21, 29) bool, the land of the ``two_sink`` basin (rows j northward, columns i east)."""
    land = np.zeros(_TWO_SINK_SHAPE, dtype=bool)
    land[:, 26:] = True
    land[17:, 20:] = True
    return land


def two_sink(swirl: float = 0.1, speed: float = 0.3, cell_size: float = 1000.0,
             n_layers: int = 1) -> FlowField:
    """The two-sink basin (module docstring); ``n_layers`` > 1 stacks `ekman_layers` 5 m
    apart."""
    swirl = validate.number("swirl", swirl)
    speed = validate.number("speed", speed, minimum=0.0, strict=True)
    cell_size = validate.number("cell_size", cell_size, minimum=0.0, strict=True)
    ny, nx = _TWO_SINK_SHAPE
    j, i = np.mgrid[0:ny, 0:nx].astype(np.float64)
    u = np.zeros((ny, nx))
    v = np.zeros((ny, nx))
    for k, (ci, cj) in enumerate(((10.0, 13.0), (20.0, 7.0))):
        g = np.exp(-((i - ci) ** 2 + (j - cj) ** 2) / 36.0)
        gx, gy = -2.0 * (i - ci) / 36.0 * g, -2.0 * (j - cj) / 36.0 * g
        u += gx
        v += gy
        if k == 0:  # k x grad(g1): clockwise around the first well
            u -= swirl * gy
            v += swirl * gx
    land = two_sink_land()
    scale = speed / np.hypot(u, v)[~land].max()
    depths = _layer_depths(n_layers)
    u, v = ekman_layers(scale * u, scale * v, depths)
    return FlowField(u, v, x=cell_size * np.arange(nx), y=cell_size * np.arange(ny),
                     depth=depths, land=np.broadcast_to(land, u.shape), crs="xy",
                     name="two_sink",
                     attrs={"source": "bounce_gym.flows.zoo.two_sink", "swirl": swirl})


# -- analytic flows ---------------------------------------------------------------------------
def _basin(basin: str, shape, cell_size: float):
    if basin not in BASINS:
        raise ConfigError(f"basin: expected one of {BASINS}, got {basin!r}")
    ny, nx = shape
    land = two_sink_land() if basin == "two_sink" else np.zeros(shape, dtype=bool)
    if land.shape != (ny, nx):
        raise ConfigError(f"shape: the two_sink basin is {_TWO_SINK_SHAPE}, got {shape}")
    return (cell_size * np.arange(nx, dtype=np.float64),
            cell_size * np.arange(ny, dtype=np.float64), land)


def _shape(shape) -> tuple[int, int]:
    if not isinstance(shape, tuple | list) or len(shape) != 2:
        raise ConfigError(f"shape: expected (rows, columns), got {shape!r}")
    return (validate.integer("shape[0]", shape[0], 2), validate.integer("shape[1]", shape[1], 2))


def solid_body(period: float = 86400.0, basin: str = "two_sink", shape=_TWO_SINK_SHAPE,
               cell_size: float = 1000.0, n_layers: int = 1) -> FlowField:
    """Counter-clockwise rotation about the grid centre, one turn per ``period`` seconds
    (negative: clockwise)."""
    period = validate.number("period", period)
    if period == 0:
        raise ConfigError("period: expected a non-zero number of seconds, got 0")
    cell_size = validate.number("cell_size", cell_size, minimum=0.0, strict=True)
    x, y, land = _basin(basin, _shape(shape), cell_size)
    xx, yy = np.meshgrid(x - x.mean(), y - y.mean())
    omega = 2 * math.pi / period
    depths = _layer_depths(n_layers)
    u, v = ekman_layers(-omega * yy, omega * xx, depths, turn_deg=0.0, e_folding=math.inf)
    return FlowField(u, v, x=x, y=y, depth=depths, land=np.broadcast_to(land, u.shape),
                     name="solid_body", attrs={"period_s": period})


def uniform(u: float = 0.2, v: float = 0.0, basin: str = "two_sink", shape=_TWO_SINK_SHAPE,
            cell_size: float = 1000.0, n_layers: int = 1) -> FlowField:
    """The velocity (u, v) m/s everywhere."""
    u, v = validate.number("u", u), validate.number("v", v)
    cell_size = validate.number("cell_size", cell_size, minimum=0.0, strict=True)
    x, y, land = _basin(basin, _shape(shape), cell_size)
    depths = _layer_depths(n_layers)
    full = np.ones((len(depths), len(y), len(x)))
    return FlowField(u * full, v * full, x=x, y=y, depth=depths,
                     land=np.broadcast_to(land, full.shape), name="uniform")


def double_gyre(A: float = 0.1, eps: float = 0.25, omega: float = 2 * math.pi / 10,
                spacing: float = 0.02, dt: float = 0.5, duration: float = 20.0) -> FlowField:
    """The time-periodic double gyre (Shadden, Lekien & Marsden 2005, Eq. 4.1) on
    [0, 2] x [0, 1]: u = -pi A sin(pi f) cos(pi y), v = pi A cos(pi f) sin(pi y) df/dx,
    f = a x^2 + b x, a = eps sin(omega t), b = 1 - 2 a."""
    A = validate.number("A", A)
    eps = validate.number("eps", eps)
    omega = validate.number("omega", omega)
    spacing = validate.number("spacing", spacing, minimum=0.0, strict=True)
    dt = validate.number("dt", dt, minimum=0.0, strict=True)
    duration = validate.number("duration", duration, minimum=0.0)
    x = np.linspace(0.0, 2.0, int(round(2.0 / spacing)) + 1)
    y = np.linspace(0.0, 1.0, int(round(1.0 / spacing)) + 1)
    t = np.arange(int(round(duration / dt)) + 1) * dt
    xx, yy = np.meshgrid(x, y)
    a = (eps * np.sin(omega * t))[:, None, None]
    b = 1.0 - 2.0 * a
    f = a * xx**2 + b * xx
    u = -math.pi * A * np.sin(math.pi * f) * np.cos(math.pi * yy)
    v = math.pi * A * np.cos(math.pi * f) * np.sin(math.pi * yy) * (2.0 * a * xx + b)
    return FlowField(u[None], v[None], x=x, y=y, time=t, name="double_gyre",
                     attrs={"A": A, "eps": eps, "omega": omega})


# -- scb_like ---------------------------------------------------------------------------------
def scb_like(seed: int = 0, n_layers: int = 3, island: bool = True, hours: float = 24.0,
             mean_speed: float = 0.15, eddy_speed: float = 0.25) -> FlowField:
    """A Southern-California-Bight-like field (module docstring), hourly from 0 to ``hours``."""
    validate.integer("seed", seed, 0)
    island = validate.flag("island", island)
    hours = validate.number("hours", hours, minimum=0.0)
    mean_speed = validate.number("mean_speed", mean_speed, minimum=0.0)
    eddy_speed = validate.number("eddy_speed", eddy_speed, minimum=0.0)
    rng = np.random.default_rng(seed)
    lat = np.round(np.linspace(33.30, 33.70, 21), 10)
    lon = np.round(np.linspace(-118.26, -117.70, 29), 10)
    # local metres east (ex) / north (ny) from the south-west corner
    m_lat = 1852.0 * 60.0
    m_lon = m_lat * math.cos(math.radians(33.5))
    ex, ny = np.meshgrid((lon - lon[0]) * m_lon, (lat - lat[0]) * m_lat)
    width, height = ex.max(), ny.max()
    # coastline through (0.45 W, top) and (right, 0.45 H): land to its north-east
    p0, p1 = np.array([0.45 * width, height]), np.array([width, 0.45 * height])
    along = (p1 - p0) / np.linalg.norm(p1 - p0)  # NW -> SE, equatorward along the coast
    normal = np.array([along[1], -along[0]])  # offshore (south-west)
    offshore = (ex - p0[0]) * normal[0] + (ny - p0[1]) * normal[1]  # metres from the coast
    coast = offshore < 0
    shelf_depth = 3.0 * offshore / 1000.0  # 3 m per km offshore
    land_island = np.zeros_like(coast)
    if island:
        land_island = ((ex - 0.3 * width) / 4000.0) ** 2 + ((ny - 0.3 * height) / 2500.0) ** 2 <= 1
    # flow pieces, m/s, on the surface
    u = mean_speed * along[0] * np.ones_like(ex)
    v = mean_speed * along[1] * np.ones_like(ex)
    # cyclonic (counter-clockwise) eddy in the west, anticyclonic one in the south
    for sense, (x0, x1), (y0, y1) in ((+1.0, (0.15, 0.4), (0.4, 0.65)),
                                      (-1.0, (0.4, 0.65), (0.1, 0.3))):
        cx, cy = rng.uniform(x0, x1) * width, rng.uniform(y0, y1) * height
        radius = rng.uniform(4000.0, 6000.0)
        dx, dy = ex - cx, ny - cy
        r2 = (dx**2 + dy**2) / radius**2
        # azimuthal speed r exp(-r^2/R^2), normalised to peak at eddy_speed (at r = R/sqrt 2)
        speed = eddy_speed * math.sqrt(2 * math.e) * np.sqrt(r2) * np.exp(-r2)
        r = np.hypot(dx, dy) + 1e-9
        u += sense * speed * (-dy / r)
        v += sense * speed * (dx / r)
    # convergence band along a SW-NE line through the domain centre: flow towards the line
    d = (ex - 0.5 * width) * (-along[0]) + (ny - 0.5 * height) * (-along[1])
    conv = -0.1 * (d / 3000.0) * np.exp(-(d / 6000.0) ** 2)
    u += conv * (-along[0])
    v += conv * (-along[1])
    # tides: a spatially uniform current ellipse along the coast, two constituents
    times = np.arange(int(math.floor(hours)) + 1) * 3600.0
    tide = np.zeros((len(times), 2))
    for amp, period_h in ((0.08, _M2_HOURS), (0.04, _K1_HOURS)):
        phase = rng.uniform(0, 2 * math.pi)
        w = 2 * math.pi / (period_h * 3600.0)
        tide[:, 0] += amp * np.cos(w * times + phase)  # along-shore
        tide[:, 1] += 0.3 * amp * np.sin(w * times + phase)  # cross-shore
    ut = u[None] + tide[:, 0, None, None] * along[0] + tide[:, 1, None, None] * normal[0]
    vt = v[None] + tide[:, 0, None, None] * along[1] + tide[:, 1, None, None] * normal[1]
    depths = _layer_depths(n_layers)
    us, vs = ekman_layers(ut, vt, depths)
    land = np.stack([coast | land_island | (shelf_depth < z) for z in depths])
    return FlowField(us, vs, x=lon, y=lat, depth=depths, time=times, land=land, crs="lonlat",
                     name="scb_like", time_origin=None,
                     attrs={"source": "bounce_gym.flows.zoo.scb_like", "seed": seed})


_FIELDS = {
    "double_gyre": double_gyre,
    "scb_like": scb_like,
    "solid_body": solid_body,
    "two_sink": two_sink,
    "uniform": uniform,
}
