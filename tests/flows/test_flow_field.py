"""FlowField (bounce_gym.flows.field): validation, land from NaN, sampling in space and time."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from bounce_gym.errors import InvalidFlowError
from bounce_gym.flows import METRES_PER_DEGREE, FlowField


def small(**overrides):
    """A 2-layer, 3-time, 4 x 5 field with u = x + 10 layer + 100 t, v = y - t."""
    x = np.array([0.0, 1.0, 2.0, 4.0, 8.0])
    y = np.array([0.0, 10.0, 20.0, 30.0])
    t = np.array([0.0, 60.0, 120.0])
    xx, yy = np.meshgrid(x, y)
    u = np.stack([[xx + 10 * k + 100 * s for s in range(3)] for k in range(2)])
    v = np.stack([[yy - s for s in range(3)] for _ in range(2)])
    kwargs = dict(u=u, v=v, x=x, y=y, depth=[0.0, 5.0], time=t)
    kwargs.update(overrides)
    return FlowField(kwargs.pop("u"), kwargs.pop("v"), **kwargs)


def test_layout_and_read_only_arrays():
    f = small()
    assert (f.n_layers, f.n_times, f.shape) == (2, 3, (4, 5))
    assert f.u.shape == f.v.shape == (2, 3, 4, 5) and f.land.shape == (2, 4, 5)
    assert not f.is_static and not f.land.any()
    for arr in (f.u, f.v, f.x, f.y, f.depth, f.time, f.land):
        with pytest.raises(ValueError):
            arr[(0,) * arr.ndim] = 1


def test_pickles_with_its_attrs_and_read_only_arrays():
    f = small(attrs={"source": "test", "seed": 3}, name="small")
    g = pickle.loads(pickle.dumps(f))
    assert dict(g.attrs) == {"source": "test", "seed": 3} and g.name == "small"
    for name in ("u", "v", "x", "y", "depth", "time", "land"):
        assert np.array_equal(getattr(g, name), getattr(f, name))
        assert not getattr(g, name).flags.writeable
    with pytest.raises(TypeError):
        g.attrs["seed"] = 4  # still a read-only mapping


def test_static_field_has_one_time_slot_and_defaults_depth():
    f = FlowField(np.ones((1, 3, 3)), np.zeros((1, 3, 3)), x=[0, 1, 2], y=[0, 1, 2])
    assert f.is_static and f.u.shape == (1, 1, 3, 3) and f.depth.tolist() == [0.0]
    u, v = f.velocity([0.3, 1.7], [0.5, 1.2], [0, 0], t=None)
    assert np.allclose(u, 1) and np.allclose(v, 0)


def test_nan_marks_land_and_is_stored_as_zero():
    u = np.ones((2, 4, 4))
    v = np.ones((2, 4, 4))
    u[1, 0, :2] = v[1, 0, :2] = np.nan
    f = FlowField(u, v, x=np.arange(4.0), y=np.arange(4.0), depth=[0, 10])
    assert f.land[1, 0, :2].all() and f.land.sum() == 2
    assert f.u[1, 0, 0, 0] == 0 and not np.isnan(f.u).any()
    assert f.water_at([0.0, 0.0], [0.0, 0.0], [0, 1]).tolist() == [True, False]


def test_land_mask_given_overrides_values_and_broadcasts_over_layers():
    land = np.zeros((4, 5), dtype=bool)
    land[0, 0] = True
    f = small(land=land)
    assert f.land[:, 0, 0].all() and f.land.sum() == 2 and (f.u[:, :, 0, 0] == 0).all()


@pytest.mark.parametrize("overrides, field, words", [
    (dict(v=np.zeros((2, 3, 4, 4))), "v", "shape"),
    (dict(u=np.zeros((2, 4, 5))), "u", "dimensions"),
    (dict(x=[0.0, 1.0, 1.0, 4.0, 8.0]), "x", "strictly increasing"),
    (dict(y=[0.0, 20.0, 10.0, 30.0]), "y", "monotonic"),
    (dict(time=[0.0, 60.0, 30.0]), "time", "strictly increasing"),
    (dict(depth=[5.0, 0.0]), "depth", "strictly increasing"),
    (dict(x=[0.0, 1.0, 2.0]), "x", "has 3 values"),
    (dict(depth=None), "depth", "required"),
    (dict(crs="utm"), "crs", "expected one of"),
    (dict(land=np.zeros((4, 5))), "land", "bool"),
    (dict(land=np.ones((4, 5), dtype=bool)), "land", "no water"),
    (dict(y=[0.0, 10.0, 20.0, 95.0], crs="lonlat"), "y", "latitudes"),
    (dict(x=[0.0, 250.0, 500.0, 750.0, 1000.0], crs="lonlat"), "x", r"longitudes must lie in "
                                                                 r"\[-360, 360\]"),
    (dict(x=[-180.0, -90.0, 0.0, 90.0, 181.0], crs="lonlat"), "x", "span at most 360 degrees"),
    (dict(u=np.full((2, 3, 4, 5), np.inf)), "u", "infinite"),
    (dict(x=["a", "b", "c", "d", "e"]), "x", "real numbers"),
])  # fmt: skip
def test_invalid_fields_name_the_argument(overrides, field, words):
    with pytest.raises(InvalidFlowError, match=rf"^{field}: .*{words}"):
        small(**overrides)


def test_nan_in_water_is_an_error():
    u = np.ones((1, 2, 3, 3))
    v = np.ones((1, 2, 3, 3))
    u[0, 1, 1, 1] = v[0, 1, 1, 1] = np.nan  # NaN at one time only
    with pytest.raises(InvalidFlowError, match=r"u: NaN in water.*\(0, 1, 1\)"):
        FlowField(u, v, x=np.arange(3.0), y=np.arange(3.0), time=[0.0, 1.0])
    u[0, :, 1, 1] = np.nan  # u NaN at both times but v finite once
    with pytest.raises(InvalidFlowError, match="^u: NaN at .* where the other component is"):
        FlowField(u, v, x=np.arange(3.0), y=np.arange(3.0), time=[0.0, 1.0])
    land = np.zeros((3, 3), dtype=bool)
    with pytest.raises(InvalidFlowError, match=r"^u: NaN in water at .*the land mask says water"):
        FlowField(u, u, x=np.arange(3.0), y=np.arange(3.0), time=[0.0, 1.0], land=land)


def test_bilinear_in_space_and_linear_in_time_on_a_nonuniform_grid():
    f = small()
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 8, 50)
    y = rng.uniform(0, 30, 50)
    layer = rng.integers(0, 2, 50)
    for t in (0.0, 45.0, 120.0):
        u, v = f.velocity(x, y, layer, t)
        # u and v are affine in x, y and t, so bilinear/linear interpolation is exact
        assert np.allclose(u, x + 10 * layer + 100 * t / 60)
        assert np.allclose(v, y - t / 60)


def test_land_nodes_count_as_zero_velocity():
    u = np.ones((1, 2, 2))
    u[0, 0, 0] = np.nan
    f = FlowField(u, u, x=[0.0, 1.0], y=[0.0, 1.0])
    uu, _ = f.velocity([0.5, 0.0, 1.0], [0.5, 0.0, 1.0], [0, 0, 0])
    assert uu.tolist() == [0.75, 0.0, 1.0]


def test_time_outside_the_range_raises_or_holds():
    f = small()
    with pytest.raises(InvalidFlowError, match=r"t: 130.0 s is outside"):
        f.velocity([1.0], [1.0], [0], 130.0)
    with pytest.raises(InvalidFlowError, match="^t: expected a finite time"):
        f.velocity([1.0], [1.0], [0], None)
    u, _ = f.velocity([1.0], [1.0], [0], 500.0, outside="hold")
    assert u[0] == pytest.approx(1.0 + 200.0)
    with pytest.raises(InvalidFlowError, match="^outside"):
        f.velocity([1.0], [1.0], [0], 10.0, outside="wrap")
    with pytest.raises(InvalidFlowError, match="^layer"):
        f.velocity([1.0], [1.0], [2], 10.0)


def test_nearest_node_and_inside():
    f = small()
    j, i, inside = f.nearest_node([0.4, 0.6, 5.9, 6.1, -0.6, 10.1], [4.0, 6.0, 0, 0, 0, 0])
    assert i.tolist() == [0, 1, 3, 4, 0, 4]
    assert j.tolist() == [0, 1, 0, 0, 0, 0]
    assert inside.tolist() == [True, True, True, True, False, False]


def test_snapshot_and_time_weights():
    f = small()
    assert f.time_weights(90.0) == (1, 2, 0.5)
    u, v = f.snapshot(90.0)
    assert np.allclose(u, 0.5 * (f.u[:, 1] + f.u[:, 2])) and u.shape == (2, 4, 5)


def test_lonlat_metric_spacing():
    lat = np.array([0.0, 60.0])
    f = FlowField(np.ones((1, 2, 3)), np.ones((1, 2, 3)), x=[10.0, 11.0, 12.0], y=lat,
                  crs="lonlat")
    dx, dy = f.metric_spacing()
    assert dx[0, 0] == pytest.approx(METRES_PER_DEGREE)
    assert dx[1, 0] == pytest.approx(0.5 * METRES_PER_DEGREE)
    assert np.allclose(dy, 60.0 * METRES_PER_DEGREE)
