"""Hand a layer of a `FlowField` to OceanParcels (v4) and advect particles there, for
cross-checks and speed comparisons with `bounce_gym.dynamics.advection`.

The layer becomes an A-grid dataset (velocities on the nodes, as in a `FlowField`) through
Parcels' public ``convert.copernicusmarine_to_sgrid``; Parcels then interpolates it bilinearly
in space and linearly in time, on a flat mesh for ``crs="xy"`` and a spherical one (60 nautical
miles per degree) for ``"lonlat"``, the same discretisation as `FlowField.velocity`. Particles
use float64 positions. Parcels is optional (``pip install bounce-gym[drifters-check]``) and
imported on first use.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.extras import require
from bounce_gym.flows.field import FlowField

__all__ = ["parcels_advect", "to_parcels_fieldset"]


def _parcels():
    require("the OceanParcels cross-check", "parcels", "xarray")
    import parcels

    return parcels


def to_parcels_fieldset(field: FlowField, layer: int = 0):
    """A `parcels.FieldSet` with the vector field ``UV`` of layer ``layer`` (land as 0)."""
    parcels = _parcels()
    import xarray as xr

    coords = {"longitude": ("longitude", field.x, {"axis": "X"}),
              "latitude": ("latitude", field.y, {"axis": "Y"}),
              "depth": ("depth", field.depth[layer:layer + 1], {"axis": "Z"})}
    if field.time is None:
        dims = ("depth", "latitude", "longitude")
        u, v = field.u[layer, 0][None], field.v[layer, 0][None]
    else:
        coords["time"] = ("time", _timedelta(field.time), {"axis": "T"})
        dims = ("time", "depth", "latitude", "longitude")
        u, v = field.u[layer][:, None], field.v[layer][:, None]
    ds = parcels.convert.copernicusmarine_to_sgrid(fields={
        "U": xr.DataArray(u, dims=dims, coords=coords),
        "V": xr.DataArray(v, dims=dims, coords=coords)})
    mesh = "spherical" if field.crs == "lonlat" else "flat"
    return parcels.FieldSet.from_sgrid_conventions(ds, mesh=mesh)


def parcels_advect(field: FlowField, x, y, layer: int, dt: float, n_steps: int,
                   t: float | None = None, fieldset=None) -> tuple[np.ndarray, np.ndarray]:
    """Positions after ``n_steps`` Parcels ``AdvectionRK4`` steps of ``dt`` seconds from time
    ``t`` (default: the field's first snapshot); ``fieldset`` reuses a `to_parcels_fieldset`."""
    parcels = _parcels()
    fieldset = to_parcels_fieldset(field, layer) if fieldset is None else fieldset
    x = np.asarray(x, dtype=np.float64)
    start = 0.0 if field.time is None else float(field.time[0])
    t0 = start if t is None else float(t)
    pclass = parcels.ParticleClass([
        parcels.Variable(var.name, dtype=np.float64 if var.dtype == np.float32 else var.dtype,
                         initial=var.initial, to_write=var.to_write, attrs=var.attrs)
        for var in parcels.Particle.variables])
    pset = parcels.ParticleSet(fieldset, pclass=pclass, x=x, y=np.asarray(y, np.float64),
                               z=np.full(len(x), field.depth[layer]),
                               t=np.full(len(x), _timedelta(t0 - start)))
    pset.execute(parcels.kernels.AdvectionRK4, dt=_timedelta(dt),
                 runtime=_timedelta(n_steps * dt), verbose_progress=False)
    return np.asarray(pset.x, dtype=np.float64), np.asarray(pset.y, dtype=np.float64)


def _timedelta(seconds):
    return np.round(np.asarray(seconds, dtype=np.float64) * 1e9).astype("timedelta64[ns]")
