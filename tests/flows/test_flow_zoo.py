"""The flow zoo (bounce_gym.flows.zoo): every field through NetCDF, and each field's defining
properties."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bounce_gym.errors import ConfigError, InvalidFlowError
from bounce_gym.flows import ekman_layers, flow_names, get_flow, load_flow, save_flow, two_sink_land


def test_names():
    assert flow_names() == ["double_gyre", "scb_like", "solid_body", "two_sink", "uniform"]


@pytest.mark.parametrize("name", flow_names())
def test_every_zoo_field_round_trips_through_netcdf(tmp_path, name):
    f = get_flow(name)
    g = load_flow(save_flow(f, tmp_path / f"{name}.nc"))
    for key in ("u", "v", "x", "y", "depth", "land"):
        assert np.array_equal(getattr(f, key), getattr(g, key)), key
    assert (f.time is None and g.time is None) or np.array_equal(f.time, g.time)
    assert (g.name, g.crs, dict(g.attrs)) == (f.name, f.crs, dict(f.attrs))


def test_unknown_names_and_arguments():
    with pytest.raises(InvalidFlowError, match="unknown flow 'gulf'; available: double_gyre"):
        get_flow("gulf")
    with pytest.raises(InvalidFlowError, match="two_sink: unknown argument 'seed'"):
        get_flow("two_sink", seed=1)
    with pytest.raises(ConfigError, match="speed"):
        get_flow("two_sink", speed=-1.0)
    with pytest.raises(ConfigError, match="basin"):
        get_flow("uniform", basin="lake")


def test_two_sink_basin_and_wells():
    f = get_flow("two_sink")
    land = two_sink_land()
    assert f.shape == (21, 29) and int(f.water.sum()) == 522
    assert land[:, 26:].all() and land[17:, 20:].all() and land.sum() == 609 - 522
    assert np.array_equal(f.land[0], land) and f.crs == "xy" and f.x[1] - f.x[0] == 1000.0
    speed = np.hypot(f.u[0, 0], f.v[0, 0])
    assert speed[~land].max() == pytest.approx(0.3)
    # two cells from each well the flow points inwards (the swirl only turns it)
    for ci, cj in ((10, 13), (20, 7)):
        for dj, di in ((2, 0), (-2, 0), (0, 2), (0, -2)):
            flow = np.array([f.u[0, 0, cj + dj, ci + di], f.v[0, 0, cj + dj, ci + di]])
            assert flow @ np.array([-di, -dj]) > 0


def test_two_sink_layers_turn_and_decay():
    f = get_flow("two_sink", n_layers=3)
    assert f.depth.tolist() == [0.0, 5.0, 10.0]
    a, s = math.radians(-40.0), math.exp(-10.0 / 20.0)
    u0, v0 = f.u[0, 0], f.v[0, 0]
    assert np.allclose(f.u[2, 0], s * (math.cos(a) * u0 - math.sin(a) * v0))
    assert np.allclose(f.v[2, 0], s * (math.sin(a) * u0 + math.cos(a) * v0))


def test_ekman_layers_keep_the_surface():
    u, v = np.ones((2, 2)), np.zeros((2, 2))
    us, vs = ekman_layers(u, v, [0.0, 20.0], turn_deg=90.0, e_folding=20.0)
    assert np.allclose(us[0], 1) and np.allclose(vs[0], 0)
    assert np.allclose(us[1], 0) and np.allclose(vs[1], math.exp(-1))


def test_scb_like_region_layers_tides_and_seed():
    f = get_flow("scb_like")
    assert f.crs == "lonlat" and f.shape == (21, 29) and f.depth.tolist() == [0.0, 5.0, 10.0]
    assert f.y[0] == pytest.approx(33.30) and f.y[-1] == pytest.approx(33.70)
    assert f.x[0] == pytest.approx(-118.26) and f.x[-1] == pytest.approx(-117.70)
    assert f.time.tolist() == [3600.0 * h for h in range(25)]
    # the coast is in the north-east; the shelf makes deeper layers lose coastal cells
    assert f.land[0, -1, -1] and not f.land[0, 0, 0]
    assert (f.land[0] <= f.land[1]).all() and (f.land[1] <= f.land[2]).all()
    assert f.land[2].sum() > f.land[0].sum()
    # tides: the field changes over the day; Ekman turn between layers 0 and 1 in open water
    assert not np.allclose(f.u[0, 1], f.u[0, 12])
    a, s = math.radians(-20.0), math.exp(-5.0 / 20.0)
    assert np.allclose(f.u[1, 7], s * (math.cos(a) * f.u[0, 7] - math.sin(a) * f.v[0, 7])
                       * ~f.land[1])
    same, other = get_flow("scb_like", seed=0), get_flow("scb_like", seed=1)
    assert np.array_equal(same.u, f.u) and not np.allclose(other.u, f.u)
    assert get_flow("scb_like", island=False).land[0].sum() < f.land[0].sum()


def test_double_gyre_matches_shadden_formula():
    f = get_flow("double_gyre")
    assert f.x[0] == 0 and f.x[-1] == 2 and f.y[-1] == 1 and f.time[-1] == 20.0
    A, eps, omega = 0.1, 0.25, 2 * math.pi / 10
    k, j, i = 7, 13, 61
    t, x, y = f.time[k], f.x[i], f.y[j]
    a = eps * math.sin(omega * t)
    b = 1 - 2 * a
    fx = a * x * x + b * x
    assert f.u[0, k, j, i] == pytest.approx(-math.pi * A * math.sin(math.pi * fx)
                                            * math.cos(math.pi * y))
    assert f.v[0, k, j, i] == pytest.approx(math.pi * A * math.cos(math.pi * fx)
                                            * math.sin(math.pi * y) * (2 * a * x + b))
    assert not f.land.any()


def test_solid_body_and_uniform():
    f = get_flow("solid_body", period=1000.0, basin="open")
    omega = 2 * math.pi / 1000.0
    xx, yy = np.meshgrid(f.x - f.x.mean(), f.y - f.y.mean())
    assert np.allclose(f.u[0, 0], -omega * yy) and np.allclose(f.v[0, 0], omega * xx)
    assert not f.land.any() and get_flow("solid_body").water.sum() == 522
    g = get_flow("uniform", u=0.1, v=-0.2)
    assert np.all(g.u[g.water[:, None]] == 0.1) and np.all(g.v[g.water[:, None]] == -0.2)
