"""`FlowField`: horizontal ocean currents on a stack of depth layers, as oceanographers hold them.

Layout (the order of CF files from ROMS, HYCOM or Copernicus after choosing one depth per layer):

* ``u`` (eastward) and ``v`` (northward) velocities in m/s, shape ``(L, T, Ny, Nx)``: layer, time,
  y (northing or latitude), x (easting or longitude). A static field has ``time is None`` and
  ``T == 1``; it is given as ``(L, Ny, Nx)`` arrays.
* ``depth``: (L,) metres, positive down, strictly increasing: **layer 0 is the surface** (the
  thesis counts layers from 1; docs/choices/drifters.md, "Drifter layers count from the surface").
* ``x`` (Nx,), ``y`` (Ny,): strictly increasing node coordinates, metres (``crs="xy"``) or
  degrees east / north (``crs="lonlat"``: latitudes in [-90, 90], longitudes in [-360, 360]
  spanning at most 360°). Node (j, i) is the centre of grid cell (j, i).
* ``time``: (T,) seconds, strictly increasing, or None; ``time_origin`` optionally names the
  instant of ``time == 0`` (an ISO 8601 string, as read from CF units ``seconds since ...``).
* ``land``: (L, Ny, Nx) bool, per layer (deeper layers may have more land: the seafloor). Land
  does not change over time. On input, NaN velocities mark land: a cell is land where u and v are
  NaN at every time; a NaN anywhere else is an error. Velocities on land are stored as 0.

Nothing is regridded, filled or clipped: an invalid field raises `InvalidFlowError` naming the
argument (``u``, ``v``, ``x``, ``y``, ``depth``, ``time``, ``land``, ``crs``) and what is allowed.

Sampling (`velocity`) is vectorised over many points: bilinear between the four surrounding nodes
(land nodes count as zero velocity, so the flow fades to zero at the coast) and linear in time
between the two surrounding snapshots; a point beyond the outermost nodes takes the value at the
nearest edge (the edge cells extend half a spacing beyond their nodes). `water_at` flags points
that lie in a water cell. For ``crs="lonlat"`` one degree of latitude is `METRES_PER_DEGREE`
(60 nautical miles, the convention OceanParcels uses), and a degree of longitude that times
cos(latitude).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from bounce_gym.errors import InvalidFlowError

__all__ = ["CRS", "MAX_LONGITUDE", "METRES_PER_DEGREE", "TIME_OUTSIDE", "FlowField"]

#: Coordinate systems: metres east/north, or degrees of longitude/latitude.
CRS = ("xy", "lonlat")
#: Metres per degree of latitude (1 nautical mile = 1852 m = one minute of arc).
METRES_PER_DEGREE = 1852.0 * 60.0
#: Longitudes lie in [-MAX_LONGITUDE, MAX_LONGITUDE] degrees (both the -180..180 and the 0..360
#: conventions, and a grid that crosses either seam) and span at most one turn.
MAX_LONGITUDE = 360.0
#: What sampling at a time outside ``[time[0], time[-1]]`` does: raise, or hold the end snapshot.
TIME_OUTSIDE = ("error", "hold")


class FlowField:
    """An immutable, validated layered flow field (see the module docstring).

    Args:
        u: eastward velocity, (L, Ny, Nx) for a static field, (L, T, Ny, Nx) with ``time``;
            m/s; NaN = land.
        v: northward velocity, shaped as ``u``.
        x: (Nx,) strictly increasing node coordinates (metres or degrees, see ``crs``).
        y: (Ny,) strictly increasing node coordinates.
        depth: (L,) metres, strictly increasing from the surface; may be omitted for one layer
            (then ``[0.0]``).
        time: (T,) seconds, strictly increasing, or None for a static field.
        land: (L, Ny, Nx) or (Ny, Nx) (the same for every layer) bool, or None to take the land
            from the NaN velocities. Given a mask, NaN velocities are allowed only on land.
        crs: ``"xy"`` or ``"lonlat"``.
        name: a label (the zoo name, or the file name).
        time_origin: the instant of ``time == 0`` (ISO 8601 string), if known.
        attrs: free-form metadata (string keys), kept and written to files.

    Raises:
        InvalidFlowError: naming the argument and what is allowed.
    """

    def __init__(self, u, v, *, x, y, depth=None, time=None, land=None, crs: str = "xy",
                 name: str = "flow", time_origin: str | None = None,
                 attrs: Mapping[str, object] | None = None) -> None:
        if crs not in CRS:
            raise InvalidFlowError(f"crs: expected one of {CRS}, got {crs!r}")
        if not isinstance(name, str):
            raise InvalidFlowError(f"name: expected a string, got {name!r}")
        if time_origin is not None and not isinstance(time_origin, str):
            raise InvalidFlowError(f"time_origin: expected a string or None, got {time_origin!r}")
        u = _velocity("u", u, static=time is None)
        v = _velocity("v", v, static=time is None)
        if v.shape != u.shape:
            raise InvalidFlowError(f"v: shape {v.shape} differs from u's {u.shape}")
        n_layers, n_times, ny, nx = u.shape
        self.x = _axis("x", x, nx)
        self.y = _axis("y", y, ny)
        if crs == "lonlat" and (self.y[0] < -90 or self.y[-1] > 90):
            raise InvalidFlowError(f"y: latitudes must lie in [-90, 90], got [{self.y[0]}, "
                                   f"{self.y[-1]}]")
        if crs == "lonlat" and (self.x[0] < -MAX_LONGITUDE or self.x[-1] > MAX_LONGITUDE
                                or self.x[-1] - self.x[0] > 360):
            raise InvalidFlowError(f"x: longitudes must lie in [-{MAX_LONGITUDE:g}, "
                                   f"{MAX_LONGITUDE:g}] and span at most 360 degrees, got "
                                   f"[{self.x[0]}, {self.x[-1]}]")
        if depth is None:
            if n_layers != 1:
                raise InvalidFlowError(f"depth: required for {n_layers} layers")
            depth = [0.0]
        self.depth = _axis("depth", depth, n_layers, minimum_size=1)
        self.time = None if time is None else _axis("time", time, n_times, minimum_size=1)
        self.land = _land(u, v, land)
        u = np.where(self.land[:, None], 0.0, u)
        v = np.where(self.land[:, None], 0.0, v)
        for arr in (u, v, self.land):
            arr.flags.writeable = False
        self.u, self.v = u, v
        self.crs = crs
        self.name = name
        self.time_origin = time_origin
        self.attrs = MappingProxyType(dict(attrs or {}))
        if not all(isinstance(k, str) for k in self.attrs):
            raise InvalidFlowError("attrs: keys must be strings")

    # -- shape ------------------------------------------------------------------------------
    @property
    def n_layers(self) -> int:
        return self.u.shape[0]

    @property
    def n_times(self) -> int:
        return self.u.shape[1]

    @property
    def shape(self) -> tuple[int, int]:
        """(Ny, Nx), the horizontal grid."""
        return self.u.shape[2], self.u.shape[3]

    @property
    def is_static(self) -> bool:
        return self.time is None

    @property
    def water(self) -> np.ndarray:
        """(L, Ny, Nx) bool, the water cells."""
        return ~self.land

    def metric_spacing(self) -> tuple[np.ndarray, np.ndarray]:
        """(dx, dy), each (Ny, Nx): the local node spacing in metres (centred differences of the
        coordinates; for ``"lonlat"`` scaled by `METRES_PER_DEGREE`, dx also by cos(latitude))."""
        ny, nx = self.shape
        dx = np.broadcast_to(np.gradient(self.x), (ny, nx)).astype(np.float64)
        dy = np.broadcast_to(np.gradient(self.y)[:, None], (ny, nx)).astype(np.float64)
        if self.crs == "lonlat":
            dx = dx * METRES_PER_DEGREE * np.cos(np.radians(self.y))[:, None]
            dy = dy * METRES_PER_DEGREE
        return dx, dy

    # -- sampling ---------------------------------------------------------------------------
    def time_weights(self, t: float | None, outside: str = "error") -> tuple[int, int, float]:
        """Snapshots ``k0, k1`` and weight ``w`` of time ``t``: the field at t is
        ``(1 - w) * field[k0] + w * field[k1]``. A static field ignores ``t``."""
        if self.time is None:
            return 0, 0, 0.0
        if outside not in TIME_OUTSIDE:
            raise InvalidFlowError(f"outside: expected one of {TIME_OUTSIDE}, got {outside!r}")
        if t is None or isinstance(t, bool) or not np.isfinite(t):
            raise InvalidFlowError(f"t: expected a finite time in seconds for the time-dependent "
                                   f"field {self.name!r}, got {t!r}")
        t = float(t)
        if (t < self.time[0] or t > self.time[-1]) and outside == "error":
            raise InvalidFlowError(f"t: {t} s is outside the field's time range "
                                   f"[{self.time[0]}, {self.time[-1]}] s")
        if len(self.time) == 1:
            return 0, 0, 0.0
        f = float(np.interp(t, self.time, np.arange(len(self.time))))
        k0 = min(int(f), len(self.time) - 2)
        return k0, k0 + 1, f - k0

    def snapshot(self, t: float | None = None, outside: str = "error"
                 ) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) at time ``t``, each (L, Ny, Nx), linear in time between snapshots."""
        k0, k1, w = self.time_weights(t, outside)
        if w == 0.0:
            return self.u[:, k0].copy(), self.v[:, k0].copy()
        return ((1 - w) * self.u[:, k0] + w * self.u[:, k1],
                (1 - w) * self.v[:, k0] + w * self.v[:, k1])

    def velocity(self, x, y, layer, t: float | None = None, outside: str = "error"
                 ) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) in m/s at points ``(x[n], y[n])`` of layers ``layer[n]`` at time ``t``:
        bilinear in space (land nodes are 0), linear in time. Arrays broadcast together."""
        x, y, layer = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(y, np.float64),
                                          np.asarray(layer))
        layer = self._layers(layer)
        j0, wy = _cell_and_weight(self.y, y)
        i0, wx = _cell_and_weight(self.x, x)
        k0, k1, wt = self.time_weights(t, outside)
        # flat indices of the four surrounding nodes in (L, T, Ny, Nx), at snapshot 0
        ny, nx = self.shape
        corners = ((layer * self.n_times * ny + j0) * nx + i0)[..., None] + (0, 1, nx, nx + 1)
        out = []
        for comp in (self.u.reshape(-1), self.v.reshape(-1)):
            val = _bilinear(comp, corners + k0 * ny * nx, wy, wx)
            if wt:
                val = (1 - wt) * val + wt * _bilinear(comp, corners + k1 * ny * nx, wy, wx)
            out.append(val)
        return out[0], out[1]

    def nearest_node(self, x, y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(j, i, inside)``: the grid cell (row j along y, column i along x) containing each
        point, and whether the point lies inside the grid's cells at all."""
        x, y = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(y, np.float64))
        j0, wy = _cell_and_weight(self.y, y)
        i0, wx = _cell_and_weight(self.x, x)
        inside = _inside(self.x, x) & _inside(self.y, y)
        return j0 + (wy >= 0.5), i0 + (wx >= 0.5), inside

    def water_at(self, x, y, layer) -> np.ndarray:
        """Bool per point: inside the grid and in a water cell of its layer."""
        x, y, layer = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(y, np.float64),
                                          np.asarray(layer))
        layer = self._layers(layer)
        j, i, inside = self.nearest_node(x, y)
        return inside & ~self.land[layer, j, i]

    def node_xy(self, j, i) -> tuple[np.ndarray, np.ndarray]:
        """Coordinates (x, y) of grid nodes (cell centres) ``(j, i)``."""
        return self.x[np.asarray(i)], self.y[np.asarray(j)]

    def _layers(self, layer: np.ndarray) -> np.ndarray:
        if layer.dtype.kind not in "iu" or np.any(layer < 0) or np.any(layer >= self.n_layers):
            raise InvalidFlowError(f"layer: expected integers in [0, {self.n_layers - 1}]")
        return layer.astype(np.intp)

    # -- pickling (environments travel to worker processes) ---------------------------------
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["attrs"] = dict(self.attrs)  # a mapping proxy does not pickle
        return state

    def __setstate__(self, state: dict) -> None:
        state["attrs"] = MappingProxyType(state["attrs"])
        self.__dict__.update(state)
        for name in ("u", "v", "land", "x", "y", "depth", "time"):
            array = getattr(self, name)
            if array is not None:
                array.flags.writeable = False

    def __repr__(self) -> str:
        time = "static" if self.time is None else f"{self.n_times} times"
        return (f"FlowField({self.name!r}, {self.n_layers} layers, {self.shape[0]}x"
                f"{self.shape[1]} {self.crs}, {time}, {int(self.water.sum())} water cells)")


# -- validation -------------------------------------------------------------------------------
def _velocity(name: str, value, *, static: bool) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        raise InvalidFlowError(f"{name}: expected real numbers in m/s, got dtype {arr.dtype}")
    want = 3 if static else 4
    if arr.ndim != want:
        dims = "(layer, y, x) for a static field" if static else "(layer, time, y, x) with time"
        raise InvalidFlowError(f"{name}: expected {want} dimensions {dims}, got shape {arr.shape}")
    arr = arr.astype(np.float64)
    if static:
        arr = arr[:, None]
    if np.isinf(arr).any():
        raise InvalidFlowError(f"{name}: infinite velocity at (layer, time, y, x) = "
                               f"{_first(np.isinf(arr))}")
    return arr


def _axis(name: str, value, size: int, minimum_size: int = 2) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf" or arr.ndim != 1:
        raise InvalidFlowError(f"{name}: expected a 1-D array of real numbers, got "
                               f"{arr.dtype} with shape {arr.shape}")
    arr = arr.astype(np.float64)
    if len(arr) != size:
        raise InvalidFlowError(f"{name}: has {len(arr)} values but the velocities have {size} "
                               f"along this dimension")
    if size < minimum_size:
        raise InvalidFlowError(f"{name}: needs at least {minimum_size} values, got {size}")
    if not np.all(np.isfinite(arr)):
        raise InvalidFlowError(f"{name}: values must be finite")
    steps = np.diff(arr)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise InvalidFlowError(f"{name}: must be strictly increasing (monotonic); "
                               f"{name}[{k}] = {arr[k]} >= {name}[{k + 1}] = {arr[k + 1]}")
    arr.flags.writeable = False
    return arr


def _land(u: np.ndarray, v: np.ndarray, land) -> np.ndarray:
    nan_u, nan_v = np.isnan(u), np.isnan(v)
    n_layers, _, ny, nx = u.shape
    if land is None:
        if not np.array_equal(nan_u, nan_v):
            which = "u" if (nan_u & ~nan_v).any() else "v"
            raise InvalidFlowError(f"{which}: NaN at (layer, time, y, x) = "
                                   f"{_first(nan_u ^ nan_v)} where the other component is "
                                   "finite; NaN marks land in both u and v")
        mask = nan_u.all(axis=1)
        partial = nan_u.any(axis=1) & ~mask
        if partial.any():
            raise InvalidFlowError(f"u: NaN in water: the cell (layer, y, x) = {_first(partial)} "
                                   "is NaN at some times only; land cannot change over time")
    else:
        mask = np.asarray(land)
        if mask.dtype != bool:
            raise InvalidFlowError(f"land: expected a bool array, got dtype {mask.dtype}")
        if mask.shape == (ny, nx):
            mask = np.broadcast_to(mask, (n_layers, ny, nx))
        if mask.shape != (n_layers, ny, nx):
            raise InvalidFlowError(f"land: expected shape {(n_layers, ny, nx)} or {(ny, nx)}, "
                                   f"got {mask.shape}")
        for name, nan in (("u", nan_u), ("v", nan_v)):
            wet_nan = nan & ~mask[:, None]
            if wet_nan.any():
                raise InvalidFlowError(f"{name}: NaN in water at (layer, time, y, x) = "
                                       f"{_first(wet_nan)} (the land mask says water)")
        mask = mask.copy()
    dry = np.flatnonzero(mask.reshape(n_layers, -1).all(axis=1))
    if len(dry):
        raise InvalidFlowError(f"land: layer {int(dry[0])} has no water cell")
    return mask


def _first(mask: np.ndarray) -> tuple[int, ...]:
    return tuple(int(k) for k in np.argwhere(mask)[0])


# -- interpolation ----------------------------------------------------------------------------
def _cell_and_weight(nodes: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower node index (so that nodes[k] <= p <= nodes[k+1], clamped to the grid) and the
    fractional position of p in that interval."""
    f = np.interp(p, nodes, np.arange(len(nodes), dtype=np.float64))
    k = np.minimum(f.astype(np.intp), len(nodes) - 2)
    return k, f - k


def _inside(nodes: np.ndarray, p: np.ndarray) -> np.ndarray:
    lo = nodes[0] - 0.5 * (nodes[1] - nodes[0])
    hi = nodes[-1] + 0.5 * (nodes[-1] - nodes[-2])
    return (p >= lo) & (p <= hi)


def _bilinear(flat: np.ndarray, corners: np.ndarray, wy, wx) -> np.ndarray:
    """Bilinear interpolation between the values ``flat[corners]`` of the nodes (j0, i0),
    (j0, i0 + 1), (j0 + 1, i0), (j0 + 1, i0 + 1) (the last axis of ``corners``), gathered
    with one `numpy.take`."""
    c = flat.take(corners)
    return ((1 - wy) * ((1 - wx) * c[..., 0] + wx * c[..., 1])
            + wy * ((1 - wx) * c[..., 2] + wx * c[..., 3]))
