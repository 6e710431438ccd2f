"""Flow fields in NetCDF (bounce_gym.flows.netcdf): round trips, other models' naming, atomic
writes, and one specific error per malformed file."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import bounce_gym.files as files
from bounce_gym.errors import ConfigError, FlowFileError
from bounce_gym.flows import FlowField, flow_from_dataset, load_flow, save_flow

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


# -- what a file may declare: checked from the header, before any array is read ---------------
def _declared(path, ny: int, nx: int, **var_kwargs) -> None:
    """u, v on (y, x) of the given lengths with no data written: a few KB on disk."""
    import netCDF4

    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("y", ny)
        nc.createDimension("x", nx)
        for name in ("x", "y"):
            nc.createVariable(name, "f8", (name,)).units = "m"
        for name in ("u", "v"):
            nc.createVariable(name, "f4", ("y", "x"), **var_kwargs).units = "m s-1"


def _peak_bytes(call) -> int:
    """The most memory (numpy arrays included) allocated while ``call`` ran."""
    import tracemalloc

    tracemalloc.start()
    try:
        call()
    except FlowFileError:
        pass
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


@pytest.mark.parametrize("cells", [10**8, 10**9])
def test_a_huge_declared_field_is_refused_before_any_array_is_read(tmp_path, cells):
    path = tmp_path / "huge.nc"
    _declared(path, 10_000, cells // 10_000)
    with pytest.raises(FlowFileError, match=rf"^{path}: u \('u'\): declares {cells:,} values \(y "
                                            r"10000 x x \d+\); at most 50,000,000 are read"):
        load_flow(path)
    assert _peak_bytes(lambda: load_flow(path)) < 20 * 2**20  # reading u alone is 400 MB+


def test_a_small_file_declaring_far_more_values_than_bytes_is_refused(tmp_path):
    """Issue 36, item 6: a 1 MB NetCDF-4 file (compressed constants, or chunks never written)
    declaring 4.8·10^7 values loaded into 1.5 GB. Under the default cap, u may declare at most
    4 values per byte of the file, or 2^22 in all."""
    path = tmp_path / "bomb.nc"
    _declared(path, 4_000, 10_000, chunksizes=(1, 10_000), zlib=True)  # a few KB
    size = path.stat().st_size
    with pytest.raises(FlowFileError, match=rf"^{path}: u \('u'\): declares 40,000,000 values "
                                            rf"in a file of {size:,} bytes \(.* per byte, about "
                                            r"1,526 MiB to load\); a file may declare at most 4 per "
                                            r"byte \(or 4,194,304 in all\) unless max_values"):
        load_flow(path)
    assert _peak_bytes(lambda: load_flow(path)) < 20 * 2**20


def test_a_given_cap_accepts_what_it_says_however_small_the_file(tmp_path, monkeypatch):
    path = tmp_path / "small.nc"
    _declared(path, 1_100, 4_000, chunksizes=(1, 4_000), zlib=True)  # 4.4·10^6 values
    with pytest.raises(FlowFileError, match="per byte"):
        load_flow(path)
    with pytest.raises(FlowFileError, match="not monotonic"):  # past the check: its unwritten y
        load_flow(path, max_values=5_000_000)
    monkeypatch.setenv("BOUNCE_GYM_MAX_FLOW_VALUES", "5000000")
    with pytest.raises(FlowFileError, match="not monotonic"):
        load_flow(path)
    _declared(path, 2_000, 2_000, chunksizes=(1, 2_000))  # 4·10^6: under 2^22 whatever its size
    monkeypatch.delenv("BOUNCE_GYM_MAX_FLOW_VALUES")
    with pytest.raises(FlowFileError, match="not monotonic"):
        load_flow(path)


def test_the_cap_counts_cells_layers_and_times_and_can_be_changed(tmp_path, monkeypatch):
    path = save_flow(field(), tmp_path / "f.nc")  # u: 2 layers x 3 times x 4 x 5 = 120 values
    with pytest.raises(FlowFileError, match=r"u \('u'\): declares 120 values \(depth 2 x time 3 x "
                                            r"lat 4 x lon 5\); at most 119 are read"):
        load_flow(path, max_values=119)
    assert same(load_flow(path, max_values=120), field())
    monkeypatch.setenv("BOUNCE_GYM_MAX_FLOW_VALUES", "119")
    with pytest.raises(FlowFileError, match="at most 119 are read"):
        load_flow(path)
    assert load_flow(path, max_values=120).shape == (4, 5)  # the argument wins
    monkeypatch.setenv("BOUNCE_GYM_MAX_FLOW_VALUES", "lots")
    with pytest.raises(ConfigError, match=r"^BOUNCE_GYM_MAX_FLOW_VALUES: expected a positive "
                                          r"integer, got 'lots'"):
        load_flow(path)
    for bad in (0, -5, 1.5, True, "120"):
        with pytest.raises(ConfigError, match="^max_values: expected an integer >= 1"):
            load_flow(path, max_values=bad)


def test_an_open_dataset_is_capped_too():
    ds = good_dataset()
    with pytest.raises(FlowFileError, match=r"^mine: u \('u'\): declares 12 values"):
        flow_from_dataset(ds, source="mine", max_values=11)
    assert flow_from_dataset(ds, max_values=12).shape == (3, 4)


def test_a_huge_coordinate_xarray_would_index_on_open_is_refused_first(tmp_path):
    import netCDF4

    path = tmp_path / "obs.nc"
    save_flow(field(), path)
    with netCDF4.Dataset(path, "a") as nc:  # an unrelated dimension with a coordinate
        nc.createDimension("obs", 10**9)
        nc.createVariable("obs", "f8", ("obs",))
    with pytest.raises(FlowFileError, match=r"^.*obs.nc: coordinate 'obs': declares "
                                            r"1,000,000,000 values"):
        load_flow(path)
    assert _peak_bytes(lambda: load_flow(path)) < 20 * 2**20  # xarray would load 8 GB


@pytest.mark.parametrize("chunks, cap, message", [
    ((20, 10, 10), 1000, r"chunks of \(20, 10, 10\) \(2,000 values, 1 chunks for time 2 x y 10 "
                         r"x x 10\); allowed are chunks of at most 1,000 values"),
    ((1, 1, 1), None, r"chunks of \(1, 1, 1\) \(1 values, 2,000,000 chunks .*at most "
                      r"1,000,000 chunks"),
])
def test_absurd_chunking_is_refused(tmp_path, chunks, cap, message):
    """One value read decompresses its whole chunk; a million chunks are a million reads."""
    import netCDF4

    path = tmp_path / "chunky.nc"
    n = 10 if cap else 1000
    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("time", None)
        for name in ("y", "x"):
            nc.createDimension(name, n)
            nc.createVariable(name, "f8", (name,)).units = "m"
        nc.createVariable("time", "f8", ("time",)).units = "seconds"
        for name in ("u", "v"):
            var = nc.createVariable(name, "f4", ("time", "y", "x"), zlib=True, chunksizes=chunks)
            var.units = "m s-1"
        nc["time"][0:2] = [0.0, 1.0]
        if cap:
            nc["u"][0:2] = nc["v"][0:2] = 0.5
    with pytest.raises(FlowFileError, match=rf"^{path}: u \('u'\): {message}"):
        load_flow(path, max_values=cap)


@pytest.mark.parametrize("where", ["global", "u"])
def test_a_huge_attribute_is_refused(tmp_path, where):
    import netCDF4

    path = save_flow(field(), tmp_path / "f.nc")
    with netCDF4.Dataset(path, "a") as nc:
        (nc if where == "global" else nc["u"]).setncattr("junk", np.zeros(2**20 + 1, np.int8))
    what = "global attribute" if where == "global" else "attribute of 'u':"
    with pytest.raises(FlowFileError, match=rf"^{path}: {what} 'junk' has 1,048,577 values; at "
                                            r"most 1,048,576 are read"):
        load_flow(path)


@pytest.mark.parametrize("fmt", ["NETCDF3_CLASSIC", "NETCDF3_64BIT_OFFSET",
                                 "NETCDF3_64BIT_DATA", "NETCDF4"])
@pytest.mark.parametrize("cut", [1, 0.5])
def test_a_truncated_file_fails_in_one_line(tmp_path, fmt, cut):
    """A classic file cut short read back zeros for the missing end, without an error."""
    full = tmp_path / "full.nc"
    xr.open_dataset(save_flow(field(), tmp_path / "f.nc"), decode_times=False).load().to_netcdf(
        full, format=fmt, engine="netcdf4")
    data = full.read_bytes()
    path = tmp_path / "cut.nc"
    path.write_bytes(data[: len(data) - 1] if cut == 1 else data[: len(data) // 2])
    message = "not a readable NetCDF file" if fmt == "NETCDF4" else "truncated NetCDF (file|header)"
    with pytest.raises(FlowFileError, match=rf"^{path}: {message}") as info:
        load_flow(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("content", [b"", b"not a netcdf file", b"CDF\x01" + b"\xff" * 60,
                                     b"CDF\x02\x00\x00\x00\x00\x00\x00\x00\x0a\x7f\xff\xff\xff",
                                     b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 4])
def test_other_files_fail_in_one_line(tmp_path, content):
    path = tmp_path / "junk.nc"
    path.write_bytes(content)
    with pytest.raises(FlowFileError, match=rf"^{path}: (not a readable NetCDF file|truncated "
                                            r"NetCDF|corrupt NetCDF)") as info:
        load_flow(path)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("variable, message", [
    ("u", r"u \('u'\): expected real numbers in m/s, got dtype <U"),
    ("x", r"x \('x'\): expected numbers, got dtype <U"),
    ("land", r"land \('land'\): expected a mask of numbers or booleans, got dtype <U"),
])
def test_strings_where_numbers_are_expected_are_refused_before_reading(tmp_path, variable,
                                                                       message):
    ds = good_dataset().assign(land=(("y", "x"), np.zeros((3, 4), np.int8),
                                     {"flag_meanings": "water land"}))
    text = np.full(ds[variable].shape, "a")
    ds = (ds.assign_coords(x=("x", text, {"units": "m"})) if variable == "x"
          else ds.assign({variable: (ds[variable].dims, text, ds[variable].attrs)}))
    path = tmp_path / "strings.nc"
    ds.to_netcdf(path)
    with pytest.raises(FlowFileError, match=rf"^{path}: {message}"):
        load_flow(path)


@pytest.mark.parametrize("lon, ok", [
    ([0.0, 500.0, 1000.0], False), ([-180.0, 0.0, 200.0], False), ([-400.0, -390.0, -380.0], False),
    ([-180.0, 0.0, 180.0], True), ([0.0, 180.0, 359.5], True), ([170.0, 180.0, 190.0], True),
    ([-360.0, -200.0, -1.0], True),
])  # fmt: skip
def test_longitudes_are_range_checked(tmp_path, lon, ok):
    ones = np.ones((2, 3))
    path = tmp_path / "lon.nc"
    xr.Dataset({"u": (("lat", "lon"), ones, VEL), "v": (("lat", "lon"), ones, VEL)},
               coords={"lon": ("lon", lon, {"units": "degrees_east"}),
                       "lat": ("lat", [10.0, 20.0], {"units": "degrees_north"})}).to_netcdf(path)
    if ok:
        assert load_flow(path).x.tolist() == lon
    else:
        with pytest.raises(FlowFileError, match=rf"^{path}: x \('lon'\): longitudes must lie in "
                                                r"\[-360, 360\] and span at most 360 degrees"):
            load_flow(path)
