"""Flow fields in CF-style NetCDF files, through xarray and the netCDF4 engine.

Writing (`save_flow`) produces one file per field:

* dimensions ``depth``, optionally ``time``, then ``y``/``x`` (``crs="xy"``, metres) or
  ``lat``/``lon`` (``crs="lonlat"``, degrees);
* ``u``, ``v`` (standard names ``eastward_sea_water_velocity``/``northward_sea_water_velocity``,
  units ``m s-1``) on ``(depth, [time,] y, x)``, NaN on land;
* ``land`` (int8, 1 = land) on ``(depth, y, x)``;
* ``depth`` (m, ``positive: down``), ``time`` (``seconds since <time_origin>``, or plain
  ``seconds`` when the origin is unknown), the field's ``name`` as the global ``title`` and its
  ``attrs`` as global attributes.

The file is written under a temporary name in the target folder and renamed into place
(`bounce_gym.files.atomic_path`), so a reader never sees half a file.

Reading (`load_flow` for a path, `flow_from_dataset` for an open `xarray.Dataset`) takes a file
from any model once its names are known. ``mapping`` names the file's variables for the keys
``u``, ``v``, ``x``, ``y``, ``depth``, ``time`` and ``land`` (non-zero = land) or ``water``
(non-zero = water, as ROMS' ``mask_rho``); e.g. Copernicus Marine
``{"u": "uo", "v": "vo"}``, HYCOM ``{"u": "water_u", "v": "water_v"}``. Keys left out are
found by CF metadata: the velocities by standard name or a usual name (`U_NAMES`, `V_NAMES`),
the dimensions of ``u`` by their coordinate's ``axis``, ``standard_name``, units or name. The
file's dimensions may come in any order and any coordinate may be decreasing (both are
reordered: no value changes); a ``positive: up`` vertical coordinate becomes depth = -z; a file
without a vertical dimension is one layer at 0 m.

Before any array is read, the file's header is checked (`bounce_gym.flows.nc_checks`): u may
declare at most ``max_values`` values (cells x layers x times; default 5·10^7, or
``$BOUNCE_GYM_MAX_FLOW_VALUES``) and, under the default cap, at most 4 values per byte of the
file (or 2^22 in all: a small compressed file would otherwise load into gigabytes), no variable
that is read may have a larger dimension or chunk, or more than 10^6 chunks, no attribute more
than 2^20 values, and a classic file must be as long as its header says; strings where numbers
are expected are refused from their dtype.

Nothing is regridded: a curvilinear grid (2-D longitude/latitude), a dimension that is not x, y,
depth or time, units other than m/s for velocities, metres or degrees for x/y, metres for depth
and a CF time unit for time all raise `FlowFileError`, as does everything `FlowField` refuses
(missing u/v, mismatched shapes, non-monotonic coordinates, NaN in water, no water). Each message
names the file, the key and the file's variable.

Engine: netCDF4 (the Unidata library) reads both the classic NetCDF-3 formats, in which many
ROMS outputs come, and HDF5-based NetCDF-4; h5netcdf reads only the latter. xarray is imported
on first use, so ``import bounce_gym`` does not pay for it.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bounce_gym.errors import BounceGymError, FlowFileError, InvalidFlowError
from bounce_gym.extras import require
from bounce_gym.files import atomic_path
from bounce_gym.flows import nc_checks
from bounce_gym.flows.field import FlowField

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["ENGINE", "MAPPING_KEYS", "U_NAMES", "V_NAMES", "flow_from_dataset",
           "flow_to_dataset", "load_flow", "save_flow"]

ENGINE = "netcdf4"
#: Keys of ``mapping``.
MAPPING_KEYS = ("u", "v", "x", "y", "depth", "time", "land", "water")
#: Usual names of the eastward / northward velocity (ours, CMEMS, HYCOM, ROMS rotated output).
U_NAMES = ("u", "uo", "water_u", "u_eastward", "U")
V_NAMES = ("v", "vo", "water_v", "v_northward", "V")
_U_STANDARD = ("eastward_sea_water_velocity", "surface_eastward_sea_water_velocity")
_V_STANDARD = ("northward_sea_water_velocity", "surface_northward_sea_water_velocity")
_AXES = {  # role -> (CF axis, standard names, usual names)
    "x": ("X", ("longitude", "projection_x_coordinate", "grid_longitude"),
          ("x", "lon", "longitude", "nav_lon")),
    "y": ("Y", ("latitude", "projection_y_coordinate", "grid_latitude"),
          ("y", "lat", "latitude", "nav_lat")),
    "depth": ("Z", ("depth", "height"), ("depth", "z", "deptht", "lev", "level")),
    "time": ("T", ("time",), ("time", "ocean_time", "t")),
}
_ROLE_ORDER = ("depth", "time", "y", "x")
_TIME_FACTORS = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0,
                 "min": 60.0, "mins": 60.0, "minute": 60.0, "minutes": 60.0,
                 "h": 3600.0, "hr": 3600.0, "hrs": 3600.0, "hour": 3600.0, "hours": 3600.0,
                 "d": 86400.0, "day": 86400.0, "days": 86400.0}
_TIME_UNITS = re.compile(r"^\s*([a-z]+)(?:\s+since\s+(.+?))?\s*$", re.IGNORECASE)


def _xr():
    """xarray, after checking that the ``drifters`` extra (xarray, netCDF4) is installed."""
    require("reading or writing a NetCDF flow file", "xarray", "netCDF4")
    import xarray as xr

    return xr


# -- writing ----------------------------------------------------------------------------------
def flow_to_dataset(field: FlowField) -> xr.Dataset:
    """The CF dataset `save_flow` writes (see the module docstring)."""
    xr = _xr()
    lonlat = field.crs == "lonlat"
    xd, yd = ("lon", "lat") if lonlat else ("x", "y")
    dims = ("depth", "time", yd, xd) if field.time is not None else ("depth", yd, xd)
    land4 = field.land[:, None]
    u = np.where(land4, np.nan, field.u)
    v = np.where(land4, np.nan, field.v)
    if field.time is None:
        u, v = u[:, 0], v[:, 0]
    velocity = {"units": "m s-1"}
    coords = {
        "depth": ("depth", field.depth, {"units": "m", "positive": "down", "axis": "Z",
                                         "standard_name": "depth"}),
        xd: (xd, field.x, {"units": "degrees_east", "standard_name": "longitude", "axis": "X"}
             if lonlat else {"units": "m", "standard_name": "projection_x_coordinate",
                             "axis": "X"}),
        yd: (yd, field.y, {"units": "degrees_north", "standard_name": "latitude", "axis": "Y"}
             if lonlat else {"units": "m", "standard_name": "projection_y_coordinate",
                             "axis": "Y"}),
    }
    if field.time is not None:
        units = "seconds" if field.time_origin is None else f"seconds since {field.time_origin}"
        coords["time"] = ("time", field.time, {"units": units, "axis": "T",
                                               "standard_name": "time"})
    for key, value in field.attrs.items():
        if not _is_attr_value(value):
            raise FlowFileError(f"attrs: {key!r} must be a string, a number or a 1-D list of "
                                f"numbers to be written to NetCDF, got {value!r}")
    ds = xr.Dataset(
        {
            "u": (dims, u, {**velocity, "standard_name": "eastward_sea_water_velocity"}),
            "v": (dims, v, {**velocity, "standard_name": "northward_sea_water_velocity"}),
            "land": (("depth", yd, xd), field.land.astype(np.int8),
                     {"flag_values": np.array([0, 1], np.int8), "flag_meanings": "water land",
                      "long_name": "land mask"}),
        },
        coords=coords,
        attrs={"Conventions": "CF-1.8", "title": field.name, **field.attrs},
    )
    return ds


def save_flow(field: FlowField, path) -> Path:
    """Write ``field`` to the NetCDF file ``path`` atomically; returns the path."""
    if not isinstance(field, FlowField):
        raise FlowFileError(f"field: expected a FlowField, got {type(field).__name__}")
    path = Path(path)
    ds = flow_to_dataset(field)
    encoding = {name: {"_FillValue": np.nan} for name in ("u", "v")}
    encoding.update({name: {"_FillValue": None} for name in ds.coords})
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine=ENGINE, format="NETCDF4", encoding=encoding)
    return path


# -- reading ----------------------------------------------------------------------------------
def load_flow(path, mapping: Mapping[str, str] | None = None, *,
              max_values: int | None = None) -> FlowField:
    """Read a flow field from a NetCDF file (see the module docstring for ``mapping``).

    ``max_values`` caps the values (cells x layers x times) the file may declare
    (`bounce_gym.flows.nc_checks`: default 5·10^7, or ``$BOUNCE_GYM_MAX_FLOW_VALUES``); under
    the default cap the file may also declare at most 4 values per byte it holds (or 2^22),
    which a given cap lifts. These, the chunking, the attributes and a classic file's length
    are checked from the header before any array is read.

    Raises:
        FlowFileError: the file is missing, not NetCDF, truncated or too large, or a variable,
            dimension or unit does not describe a valid field; one line naming the file, the key
            and the variable.
    """
    path = Path(path)
    if not path.is_file():
        raise FlowFileError(f"{path}: no such file")
    cap = nc_checks.max_values(max_values)
    # under the default cap, a file may not declare far more values than it has bytes
    file_bytes = None if nc_checks.explicit_cap(max_values) else path.stat().st_size
    xr = _xr()
    _check_file(path, cap)
    try:
        ds = xr.open_dataset(path, engine=ENGINE, decode_times=False, decode_timedelta=False,
                             mask_and_scale=True)
    except (OSError, ValueError, RuntimeError) as exc:
        raise FlowFileError(f"{path}: not a readable NetCDF file ({_one_line(exc)})") from None
    with ds:
        return _flow(ds, mapping, str(path), path.stem, cap, file_bytes)


def _check_file(path: Path, cap: int) -> None:
    """`check_classic`, then `check_header` on the file opened with netCDF4 (which reads only
    its header)."""
    import netCDF4

    try:
        nc_checks.check_classic(path)
        with netCDF4.Dataset(path) as nc:
            nc_checks.check_header(nc, path, cap)
    except BounceGymError:
        raise
    except (OSError, RuntimeError, ValueError, UnicodeError) as exc:
        raise FlowFileError(f"{path}: not a readable NetCDF file ({_one_line(exc)})") from None


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


def flow_from_dataset(ds: xr.Dataset, mapping: Mapping[str, str] | None = None, *,
                      source: str = "dataset", name: str | None = None,
                      max_values: int | None = None) -> FlowField:
    """A `FlowField` from an open dataset (see `load_flow`); ``source`` prefixes messages.
    ``max_values`` caps the values u may declare, as in `load_flow`; nothing is read before the
    variables to read are checked against it."""
    return _flow(ds, mapping, source, name, nc_checks.max_values(max_values), None)


def _flow(ds: xr.Dataset, mapping: Mapping[str, str] | None, source: str, name: str | None,
          cap: int, file_bytes: int | None) -> FlowField:
    """`flow_from_dataset` with the checked cap; ``file_bytes``: the size of the file ``ds``
    was opened from, whose values `nc_checks.check_expansion` bounds (None: not checked)."""
    names = _check_mapping(mapping, ds, source)
    u_name = names.get("u") or _find_velocity(ds, "u", _U_STANDARD, U_NAMES, source)
    v_name = names.get("v") or _find_velocity(ds, "v", _V_STANDARD, V_NAMES, source)
    names.update(u=u_name, v=v_name)
    u_var, v_var = ds[u_name], ds[v_name]
    if dict(u_var.sizes) != dict(v_var.sizes):
        raise FlowFileError(f"{source}: v ({v_name!r}): dimensions {dict(v_var.sizes)} differ "
                            f"from u's ({u_name!r}) {dict(u_var.sizes)}")
    for key, var in (("u", u_var), ("v", v_var)):
        _check_velocity_units(var, key, source)
        _check_readable(var, f"{key} ({var.name!r})", source, cap, "real numbers in m/s")
    if file_bytes is not None:
        nc_checks.check_expansion(source, f"u ({u_var.name!r})", dict(u_var.sizes), file_bytes)
    roles = _dimension_roles(ds, u_var, names, source)
    coords = {role: _coordinate(ds, dim, role, names, source, cap)
              for role, dim in roles.items()}
    crs = _crs(ds, roles, names, source)
    order = [roles[r] for r in _ROLE_ORDER if r in roles]
    flips = {roles[r]: slice(None, None, -1) for r, c in coords.items()
             if len(c) > 1 and c[0] > c[-1]}
    u = u_var.transpose(*order).isel(flips).values
    v = v_var.transpose(*order).isel(flips).values
    coords = {r: (c[::-1] if roles[r] in flips else c) for r, c in coords.items()}
    if "depth" not in roles:
        u, v = u[None], v[None]
    land = _land_mask(ds, roles, names, flips, source, cap)
    time_origin = None
    if "time" in roles:
        coords["time"], time_origin = _time(ds[names.get("time", roles["time"])], coords["time"],
                                            source)
    attrs = {k: _plain(v) for k, v in ds.attrs.items() if k not in ("Conventions", "title")}
    try:
        return FlowField(u, v, x=coords["x"], y=coords["y"], depth=coords.get("depth", [0.0]),
                         time=coords.get("time"), land=land, crs=crs,
                         name=str(ds.attrs.get("title", name or source)),
                         time_origin=time_origin, attrs=attrs)
    except InvalidFlowError as exc:
        key, _, rest = str(exc).partition(": ")
        label = f"{key} ({names[key]!r})" if key in names else key
        if key in roles and key not in names:
            label = f"{key} ({roles[key]!r})"
        raise FlowFileError(f"{source}: {label}: {rest}") from None


def _check_readable(var, label: str, source: str, cap: int, what: str,
                    kinds: str = "iuf", hint: str = "") -> None:
    """Before ``var`` is read: its dtype (one of ``kinds``), declared size and chunking."""
    if var.dtype.kind not in kinds:
        raise FlowFileError(f"{source}: {label}: expected {what}, got dtype {var.dtype}{hint}")
    nc_checks.check_variable(source, label, dict(var.sizes), var.encoding.get("chunksizes"),
                             cap)


def _check_mapping(mapping, ds, source: str) -> dict[str, str]:
    if mapping is None:
        return {}
    if not isinstance(mapping, Mapping):
        raise FlowFileError(f"mapping: expected a dict of {MAPPING_KEYS} to variable names, got "
                            f"{mapping!r}")
    out = {}
    for key, value in mapping.items():
        if key not in MAPPING_KEYS:
            raise FlowFileError(f"mapping: unknown key {key!r}; allowed: {MAPPING_KEYS}")
        if not isinstance(value, str) or value not in ds.variables:
            raise FlowFileError(f"{source}: {key}: mapped to {value!r}, which is not a variable "
                                f"of the file; variables: {sorted(map(str, ds.variables))}")
        out[key] = value
    if "land" in out and "water" in out:
        raise FlowFileError("mapping: give 'land' or 'water', not both")
    return out


def _find_velocity(ds, key: str, standard: tuple[str, ...], usual: tuple[str, ...],
                   source: str) -> str:
    by_standard = [str(n) for n, var in ds.data_vars.items()
                   if var.attrs.get("standard_name") in standard]
    found = by_standard or [n for n in usual if n in ds.data_vars]
    if len(found) == 1:
        return found[0]
    if not found:
        raise FlowFileError(
            f"{source}: {key}: missing; no variable has standard_name {' or '.join(standard)} or "
            f"is called {', '.join(usual)}; name it with mapping={{'{key}': ...}}; variables: "
            f"{sorted(map(str, ds.data_vars))}")
    raise FlowFileError(f"{source}: {key}: ambiguous, candidates {found}; choose one with "
                        f"mapping={{'{key}': ...}}")


def _check_velocity_units(var, key: str, source: str) -> None:
    units = var.attrs.get("units")
    if units is None:
        raise FlowFileError(f"{source}: {key} ({var.name!r}): no units attribute; expected "
                            "m s-1")
    if _normal_units(units) not in ("m/s", "ms-1"):
        raise FlowFileError(f"{source}: {key} ({var.name!r}): wrong units {units!r}; expected "
                            "m s-1 (nothing is converted)")


def _normal_units(units: str) -> str:
    text = str(units).strip().lower()
    for long, short in (("metres", "m"), ("meters", "m"), ("metre", "m"), ("meter", "m"),
                        ("seconds", "s"), ("second", "s"), ("sec", "s"), (" per ", "/")):
        text = text.replace(long, short)
    return re.sub(r"[\s.*^]", "", text).replace("**", "")


def _dimension_roles(ds, u_var, names: dict[str, str], source: str) -> dict[str, str]:
    roles: dict[str, str] = {}
    for role in ("x", "y", "depth", "time"):
        if role in names:
            var = ds[names[role]]
            if var.ndim != 1 or var.dims[0] not in u_var.dims:
                raise FlowFileError(
                    f"{source}: {role} ({names[role]!r}): expected a 1-D coordinate along one of "
                    f"u's dimensions {u_var.dims}, got dimensions {var.dims}")
            roles[role] = str(var.dims[0])
    for dim in u_var.dims:
        if dim in roles.values():
            continue
        role = _role_of(ds, str(dim))
        if role is None:
            raise FlowFileError(
                f"{source}: u ({u_var.name!r}): dimension {dim!r} is not x, y, depth or time "
                "(or has no 1-D coordinate variable: curvilinear grids are not supported, "
                "nothing is regridded); select one value first or name the axes with mapping")
        if role in roles:
            raise FlowFileError(f"{source}: {role}: both {roles[role]!r} and {dim!r} look like "
                                f"the {role} dimension; choose with mapping={{'{role}': ...}}")
        roles[role] = str(dim)
    for role in ("x", "y"):
        if role not in roles:
            raise FlowFileError(f"{source}: {role}: u ({u_var.name!r}) has no {role} dimension; "
                                f"its dimensions are {u_var.dims}")
    return roles


def _role_of(ds, dim: str) -> str | None:
    if dim not in ds.variables or ds[dim].ndim != 1:
        return None
    attrs = ds[dim].attrs
    units = _normal_units(attrs.get("units", ""))
    for role, (axis, standard, _) in _AXES.items():
        if attrs.get("axis") == axis or attrs.get("standard_name") in standard:
            return role
    if units.startswith(("degrees_e", "degree_e")):
        return "x"
    if units.startswith(("degrees_n", "degree_n")):
        return "y"
    for role, (_, _, usual) in _AXES.items():
        if dim in usual:
            return role
    return None


def _coordinate(ds, dim: str, role: str, names: dict[str, str], source: str,
                cap: int) -> np.ndarray:
    var = ds[names.get(role, dim)]
    label = f"{role} ({var.name!r})"
    _check_readable(var, label, source, cap, "numbers",
                    hint=" (open the file with decode_times=False)")
    values = np.asarray(var.values).astype(np.float64)
    steps = np.diff(values)
    if len(values) > 1 and not (np.all(steps > 0) or np.all(steps < 0)):
        raise FlowFileError(f"{source}: {label}: not monotonic (values must strictly increase "
                            "or strictly decrease)")
    if role == "depth":
        units = _normal_units(var.attrs.get("units", ""))
        if units not in ("m",):
            raise FlowFileError(f"{source}: {label}: wrong units {var.attrs.get('units')!r}; "
                                "expected m (fixed depths; sigma or level numbers are not "
                                "depths)")
        if str(var.attrs.get("positive", "down")).lower() == "up":
            values = -values
    return values


def _crs(ds, roles: dict[str, str], names: dict[str, str], source: str) -> str:
    kinds = {}
    for role, want in (("x", "east"), ("y", "north")):
        var = ds[names.get(role, roles[role])]
        units = _normal_units(var.attrs.get("units", ""))
        geographic = var.attrs.get("standard_name") in ("longitude", "latitude")
        if units == "m":
            kinds[role] = "xy"
        elif units in (f"degrees_{want}", f"degree_{want}", f"degrees{want[0]}",
                       f"degree{want[0]}", f"degrees_{want[0]}", f"degree_{want[0]}") or (
                units in ("", "degrees", "degree") and geographic):
            kinds[role] = "lonlat"
        else:
            raise FlowFileError(
                f"{source}: {role} ({var.name!r}): wrong units {var.attrs.get('units')!r}; "
                f"expected m or degrees_{want} (nothing is converted)")
    if kinds["x"] != kinds["y"]:
        raise FlowFileError(f"{source}: y: units {kinds['y']} do not match x's {kinds['x']}")
    return kinds["x"]


def _land_mask(ds, roles, names, flips, source: str, cap: int):
    key = "land" if "land" in names else "water" if "water" in names else None
    if key is None:
        if "land" not in ds.data_vars or "flag_meanings" not in ds["land"].attrs:
            return None  # NaN velocities mark the land
        key, names = "land", {**names, "land": "land"}
    var = ds[names[key]]
    by_dim = {dim: role for role, dim in roles.items()}
    if any(dim not in by_dim or by_dim[dim] == "time" for dim in var.dims) or not (
            {roles["x"], roles["y"]} <= set(var.dims)):
        raise FlowFileError(f"{source}: {key} ({var.name!r}): expected dimensions (y, x) or "
                            f"(depth, y, x) of u, got {var.dims}")
    order = [roles[r] for r in ("depth", "y", "x") if r in roles and roles[r] in var.dims]
    _check_readable(var, f"{key} ({var.name!r})", source, cap, "a mask of numbers or booleans",
                    "biuf")
    values = var.transpose(*order).isel({d: s for d, s in flips.items() if d in var.dims}).values
    if values.dtype.kind == "f" and np.isnan(values).any():
        raise FlowFileError(f"{source}: {key} ({var.name!r}): NaN in the mask")
    mask = values != 0
    return mask if key == "land" else ~mask


def _time(var, values: np.ndarray, source: str) -> tuple[np.ndarray, str | None]:
    units = var.attrs.get("units")
    match = _TIME_UNITS.match(str(units)) if units is not None else None
    if match is None or match.group(1).lower() not in _TIME_FACTORS:
        raise FlowFileError(f"{source}: time ({var.name!r}): wrong units {units!r}; expected "
                            "'<seconds|minutes|hours|days> [since <date>]'")
    return values * _TIME_FACTORS[match.group(1).lower()], match.group(2)


def _plain(value):
    """A NetCDF attribute as a Python value: numpy scalars as numbers, arrays as lists."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def _is_attr_value(value) -> bool:
    if isinstance(value, bool):
        return False
    if isinstance(value, str | int | float | np.integer | np.floating):
        return True
    arr = np.asarray(value)
    return arr.ndim == 1 and arr.dtype.kind in "iuf"
