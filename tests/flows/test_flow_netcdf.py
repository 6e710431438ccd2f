"""Flow fields in NetCDF (bounce_gym.flows.netcdf): round trips, other models' naming, atomic
writes, and one specific error per malformed file."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import bounce_gym.files as files
from bounce_gym.errors import FlowFileError
from bounce_gym.flows import FlowField, load_flow, save_flow

VEL = {"units": "m s-1"}


def field(**overrides):
    rng = np.random.default_rng(0)
    u = rng.normal(size=(2, 3, 4, 5))
    v = rng.normal(size=(2, 3, 4, 5))
    u[1, :, 0, 0] = v[1, :, 0, 0] = np.nan
    kwargs = dict(x=np.linspace(-118.2, -118.0, 5), y=np.linspace(33.3, 33.6, 4),
                  depth=[0.0, 5.0], time=[0.0, 3600.0, 7200.0], crs="lonlat", name="small",
                  time_origin="2011-07-01 00:00:00", attrs={"source": "test", "seed": 3,
                                                            "scale": [1.5, 2.5]})
    kwargs.update(overrides)
    return FlowField(u, v, **kwargs)


def same(a: FlowField, b: FlowField) -> bool:
    arrays = all(np.array_equal(getattr(a, k), getattr(b, k))
                 for k in ("u", "v", "x", "y", "depth", "land"))
    times = (a.time is None and b.time is None) or np.array_equal(a.time, b.time)
    return arrays and times and (a.crs, a.name, a.time_origin, dict(a.attrs)) == (
        b.crs, b.name, b.time_origin, dict(b.attrs))


@pytest.mark.parametrize("overrides", [
    {},
    dict(time_origin=None),
    dict(crs="xy", x=np.arange(5) * 1e3, y=np.arange(4) * 1e3, attrs={}),
])  # fmt: skip
def test_round_trip_keeps_values_coordinates_attributes_and_mask(tmp_path, overrides):
    f = field(**overrides)
    g = load_flow(save_flow(f, tmp_path / "f.nc"))
    assert same(f, g) and g.land[1, 0, 0] and g.land.sum() == 1


def test_static_field_round_trip_has_no_time_dimension(tmp_path):
    f = FlowField(np.ones((1, 3, 3)), np.zeros((1, 3, 3)), x=[0.0, 1.0, 2.0], y=[0.0, 1.0, 2.0])
    path = save_flow(f, tmp_path / "s.nc")
    with xr.open_dataset(path) as ds:
        assert "time" not in ds.dims
        assert ds.u.attrs["standard_name"] == "eastward_sea_water_velocity"
    assert same(f, load_flow(path))


def test_written_file_is_cf_style(tmp_path):
    with xr.open_dataset(save_flow(field(), tmp_path / "f.nc"), decode_times=False) as ds:
        assert ds.attrs["Conventions"].startswith("CF-")
        assert ds.u.dims == ("depth", "time", "lat", "lon") and ds.u.attrs["units"] == "m s-1"
        assert ds.lon.attrs["units"] == "degrees_east" and ds.depth.attrs["positive"] == "down"
        assert ds.time.attrs["units"] == "seconds since 2011-07-01 00:00:00"
        assert np.isnan(ds.u.values[1, :, 0, 0]).all()


def test_copernicus_like_file_loads_without_mapping(tmp_path):
    """CMEMS naming: uo/vo, latitude decreasing, hours since, NaN land, no land variable."""
    lat = np.array([33.6, 33.5, 33.4])
    lon = np.array([-118.2, -118.1, -118.0, -117.9])
    uo = np.arange(2 * 2 * 3 * 4, dtype=float).reshape(2, 2, 3, 4)  # time, depth, lat, lon
    uo[:, :, 0, 3] = np.nan
    ds = xr.Dataset(
        {"uo": (("time", "depth", "latitude", "longitude"), uo,
                {"units": "m s-1", "standard_name": "eastward_sea_water_velocity"}),
         "vo": (("time", "depth", "latitude", "longitude"), -uo,
                {"units": "m/s", "standard_name": "northward_sea_water_velocity"})},
        coords={"time": ("time", [0.0, 1.0], {"units": "hours since 2011-07-01"}),
                "depth": ("depth", [0.5, 5.0], {"units": "m", "positive": "down"}),
                "latitude": ("latitude", lat, {"units": "degrees_north"}),
                "longitude": ("longitude", lon, {"units": "degrees_east"})})
    ds.to_netcdf(tmp_path / "cmems.nc")
    f = load_flow(tmp_path / "cmems.nc")
    assert f.crs == "lonlat" and f.time.tolist() == [0.0, 3600.0]
    assert f.time_origin == "2011-07-01" and f.y.tolist() == lat[::-1].tolist()
    # the value at (time 1, depth 1, lat 33.6, lon -118.1) is unchanged by the reordering
    assert f.u[1, 1, 2, 1] == uo[1, 1, 0, 1] and f.v[1, 1, 2, 1] == -uo[1, 1, 0, 1]
    assert f.land[:, 2, 3].all() and f.land.sum() == 2


def test_mapping_names_a_models_variables_and_water_mask(tmp_path):
    """ROMS-style names with 1-D coordinates and a mask that is 1 on water."""
    mask = np.ones((3, 4))
    mask[0, 0] = 0
    ds = xr.Dataset(
        {"u_eastward": (("s", "eta", "xi"), np.ones((1, 3, 4)), VEL),
         "v_northward": (("s", "eta", "xi"), np.ones((1, 3, 4)), VEL),
         "mask_rho": (("eta", "xi"), mask),
         "xr": ("xi", [0.0, 1e3, 2e3, 3e3], {"units": "meter"}),
         "yr": ("eta", [0.0, 1e3, 2e3], {"units": "meter"}),
         "zr": ("s", [-2.0], {"units": "m", "positive": "up"})})
    ds.to_netcdf(tmp_path / "roms.nc")
    f = load_flow(tmp_path / "roms.nc", mapping={
        "u": "u_eastward", "v": "v_northward", "x": "xr", "y": "yr", "depth": "zr",
        "water": "mask_rho"})
    assert f.crs == "xy" and f.depth.tolist() == [2.0] and f.land[0, 0, 0] and f.land.sum() == 1


def test_surface_product_without_depth_is_one_layer_at_zero(tmp_path):
    ones = np.ones((2, 3))
    ds = xr.Dataset({"u": (("y", "x"), ones, VEL), "v": (("y", "x"), ones, VEL)},
                    coords={"x": ("x", [0.0, 1.0, 2.0], {"units": "m"}),
                            "y": ("y", [0.0, 1.0], {"units": "m"})})
    ds.to_netcdf(tmp_path / "hf.nc")
    f = load_flow(tmp_path / "hf.nc")
    assert f.n_layers == 1 and f.depth.tolist() == [0.0] and f.is_static


def test_classic_netcdf3_files_are_read(tmp_path):
    path = tmp_path / "classic.nc"
    xr.open_dataset(save_flow(field(), tmp_path / "f.nc"), decode_times=False).load().to_netcdf(
        path, format="NETCDF3_64BIT", engine="netcdf4")
    assert same(field(), load_flow(path))


# -- atomic writes ----------------------------------------------------------------------------
def test_save_overwrites_and_leaves_no_temporary_file(tmp_path):
    save_flow(field(), tmp_path / "f.nc")
    save_flow(field(name="second"), tmp_path / "f.nc")
    assert load_flow(tmp_path / "f.nc").name == "second"
    assert [p.name for p in tmp_path.iterdir()] == ["f.nc"]


def test_failed_save_keeps_the_old_file(tmp_path, monkeypatch):
    path = save_flow(field(), tmp_path / "f.nc")
    before = path.read_bytes()

    def broken_replace(src, dst):
        raise OSError("disk on fire")

    monkeypatch.setattr(files.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk on fire"):
        save_flow(field(name="second"), path)
    assert path.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["f.nc"]


def test_unwritable_attribute_is_refused_before_writing(tmp_path):
    with pytest.raises(FlowFileError, match="attrs: 'flag'"):
        save_flow(field(attrs={"flag": True}), tmp_path / "f.nc")
    assert list(tmp_path.iterdir()) == []


# -- malformed files: one error each, naming the field ----------------------------------------
def good_dataset() -> xr.Dataset:
    u = np.ones((1, 3, 4))
    return xr.Dataset({"u": (("depth", "y", "x"), u, VEL), "v": (("depth", "y", "x"), u, VEL)},
                      coords={"x": ("x", [0.0, 1.0, 2.0, 3.0], {"units": "m"}),
                              "y": ("y", [0.0, 1.0, 2.0], {"units": "m"}),
                              "depth": ("depth", [0.0], {"units": "m"})})


def broken(kind: str) -> xr.Dataset:
    ds = good_dataset()
    if kind == "missing u":
        return ds.drop_vars("u")
    if kind == "mismatched shapes":
        return ds.assign(v=(("depth", "y", "x2"), np.ones((1, 3, 2)), VEL)).assign_coords(
            x2=("x2", [0.0, 1.0], {"units": "m"}))
    if kind == "non-monotonic x":
        return ds.assign_coords(x=("x", [0.0, 2.0, 1.0, 3.0], {"units": "m"}))
    if kind == "NaN in water":
        u = ds.u.values.copy()
        u[0, 1, 1] = np.nan
        return ds.assign(u=(ds.u.dims, u, VEL), land=(("y", "x"), np.zeros((3, 4), np.int8),
                                                      {"flag_meanings": "water land"}))
    if kind == "no water":
        nan = np.full((1, 3, 4), np.nan)
        return ds.assign(u=(ds.u.dims, nan, VEL), v=(ds.v.dims, nan, VEL))
    if kind == "wrong velocity units":
        return ds.assign(u=(ds.u.dims, ds.u.values, {"units": "cm s-1"}))
    if kind == "no velocity units":
        return ds.assign(v=(ds.v.dims, ds.v.values))
    if kind == "wrong x units":
        return ds.assign_coords(x=("x", ds.x.values, {"units": "km"}))
    if kind == "sigma depth":
        return ds.assign_coords(depth=("depth", [-0.5], {"long_name": "s-coordinate"}))
    if kind == "bad time units":
        u = np.ones((1, 2, 3, 4))
        return ds.assign(u=(("depth", "time", "y", "x"), u, VEL),
                         v=(("depth", "time", "y", "x"), u, VEL)).assign_coords(
            time=("time", [0.0, 1.0], {"units": "fortnights"}))
    if kind == "extra dimension":
        u = np.ones((2, 1, 3, 4))
        return ds.assign(u=(("member", "depth", "y", "x"), u, VEL),
                         v=(("member", "depth", "y", "x"), u, VEL))
    if kind == "curvilinear":
        u = np.ones((3, 4))
        return xr.Dataset({"u": (("eta_rho", "xi_rho"), u, VEL),
                           "v": (("eta_rho", "xi_rho"), u, VEL),
                           "lon_rho": (("eta_rho", "xi_rho"), u)})
    if kind == "ambiguous u":
        return ds.assign(uo=ds.u)
    raise AssertionError(kind)


@pytest.mark.parametrize("kind, message", [
    ("missing u", r"u: missing; no variable has standard_name eastward_sea_water_velocity"),
    ("mismatched shapes", r"v \('v'\): dimensions .* differ from u's"),
    ("non-monotonic x", r"x \('x'\): not monotonic"),
    ("NaN in water", r"u \('u'\): NaN in water at \(layer, time, y, x\) = \(0, 0, 1, 1\)"),
    ("no water", r"land: layer 0 has no water cell"),
    ("wrong velocity units", r"u \('u'\): wrong units 'cm s-1'; expected m s-1"),
    ("no velocity units", r"v \('v'\): no units attribute"),
    ("wrong x units", r"x \('x'\): wrong units 'km'"),
    ("sigma depth", r"depth \('depth'\): wrong units None; expected m"),
    ("bad time units", r"time \('time'\): wrong units 'fortnights'"),
    ("extra dimension", r"u \('u'\): dimension 'member' is not x, y, depth or time"),
    ("curvilinear", r"u \('u'\): dimension 'eta_rho' .*curvilinear grids are not supported"),
    ("ambiguous u", r"u: ambiguous, candidates \['u', 'uo'\]"),
])  # fmt: skip
def test_malformed_file_raises_naming_the_field(tmp_path, kind, message):
    path = tmp_path / f"{kind.replace(' ', '_')}.nc"
    broken(kind).to_netcdf(path)
    with pytest.raises(FlowFileError, match=rf"^{path}: {message}"):
        load_flow(path)


def test_missing_and_non_netcdf_files(tmp_path):
    with pytest.raises(FlowFileError, match="no such file"):
        load_flow(tmp_path / "nothing.nc")
    (tmp_path / "text.nc").write_text("not a netcdf file")
    with pytest.raises(FlowFileError, match="not a readable NetCDF file"):
        load_flow(tmp_path / "text.nc")


def test_bad_mappings(tmp_path):
    path = tmp_path / "good.nc"
    good_dataset().to_netcdf(path)
    with pytest.raises(FlowFileError, match="mapping: unknown key 'speed'"):
        load_flow(path, mapping={"speed": "u"})
    with pytest.raises(FlowFileError, match=r"u: mapped to 'uo', which is not a variable"):
        load_flow(path, mapping={"u": "uo"})
    with pytest.raises(FlowFileError, match="mapping: expected a dict"):
        load_flow(path, mapping=["u"])
    assert load_flow(path, mapping={"u": "u", "x": "x"}).shape == (3, 4)
