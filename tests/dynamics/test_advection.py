"""Continuous drifters (bounce_gym.dynamics.advection): RK4 accuracy, diffusion, the land rules,
layer changes and input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bounce_gym.cells import DOWN, DRIFT, UP
from bounce_gym.dynamics.advection import Drifters
from bounce_gym.errors import ActionError, ConfigError, InvalidFlowError
from bounce_gym.flows import get_flow


def test_solid_body_orbits_close_after_one_period():
    f = get_flow("solid_body", period=86400.0, basin="open")
    cx, cy = f.x.mean(), f.y.mean()
    r = np.array([2e3, 5e3, 8e3])
    d = Drifters(f, cx + r, np.full(3, cy))
    xs, ys = d.run(86400.0 / 240, 240)
    radius = np.hypot(xs - cx, ys - cy)
    assert np.abs(radius - r).max() < 1e-6 * r.max()
    assert np.abs(xs[-1] - (cx + r)).max() < 1e-6 * r.max()
    assert np.abs(ys[-1] - cy).max() < 1e-6 * r.max()
    quarter = np.hypot(xs[60] - cx, ys[60] - (cy + r))  # a quarter turn later: due north
    assert quarter.max() < 1e-6 * r.max()
    assert d.t == pytest.approx(86400.0)


def test_uniform_flow_moves_exactly_and_lonlat_converts_metres_to_degrees():
    f = get_flow("uniform", u=0.2, v=-0.1, basin="open")
    d = Drifters(f, [5e3], [15e3])
    d.run(100.0, 50)
    assert d.x[0] == pytest.approx(5e3 + 0.2 * 5000) and d.y[0] == pytest.approx(15e3 - 500)
    g = get_flow("scb_like", mean_speed=0.0, eddy_speed=0.0)  # tides and convergence only
    lon, lat = -118.0, 33.4
    d = Drifters(g, [lon], [lat], t=0.0)
    u, v = g.velocity([lon], [lat], [0], 0.0)
    d.step(1.0)
    metres_east = (d.x[0] - lon) * 1852 * 60 * math.cos(math.radians(lat))
    assert metres_east == pytest.approx(u[0], rel=1e-4)
    assert (d.y[0] - lat) * 1852 * 60 == pytest.approx(v[0], rel=1e-4)


def test_diffusion_spreads_with_variance_2kt_and_is_seeded():
    f = get_flow("uniform", u=0.0, v=0.0, basin="open")
    n, k, dt, steps = 4000, 0.5, 10.0, 50
    start = np.full(n, 14e3), np.full(n, 10e3)
    d = Drifters(f, *start, diffusivity=k, rng=3)
    d.run(dt, steps)
    var = 2 * k * dt * steps
    assert np.var(d.x - start[0]) == pytest.approx(var, rel=0.1)
    assert np.var(d.y - start[1]) == pytest.approx(var, rel=0.1)
    again = Drifters(f, *start, diffusivity=k, rng=np.random.default_rng(3))
    again.run(dt, steps)
    assert np.array_equal(again.x, d.x)
    other = Drifters(f, *start, diffusivity=k, rng=4)
    other.run(dt, steps)
    assert not np.array_equal(other.x, d.x)


def test_land_rule_stay_stops_at_the_coast():
    f = get_flow("uniform", u=0.3, v=0.1)  # towards the land strip east of column 25
    d = Drifters(f, np.full(5, 20e3), np.linspace(2e3, 10e3, 5), land_rule="stay")
    held = np.zeros(5, dtype=bool)
    for _ in range(100):
        held |= d.step(300.0)
        assert f.water_at(d.x, d.y, d.layer).all()
    assert held.all() and (d.x <= 25.5e3).all()
    before = d.x.copy(), d.y.copy()
    assert d.step(300.0).all()  # stuck: every further step is held back whole
    assert np.array_equal(d.x, before[0]) and np.array_equal(d.y, before[1])


def test_land_rule_slide_keeps_the_move_along_the_coast():
    f = get_flow("uniform", u=0.3, v=0.1)
    d = Drifters(f, np.full(5, 20e3), np.linspace(2e3, 10e3, 5), land_rule="slide")
    for _ in range(100):
        d.step(300.0)
        assert f.water_at(d.x, d.y, d.layer).all()
    x_before, y_before = d.x.copy(), d.y.copy()
    assert d.step(300.0).all()
    # the eastward part is cut at the coast; the northward part goes on, slowed by the zero
    # velocity of the land nodes next to the drifter
    assert np.array_equal(d.x, x_before) and (d.x <= 25.5e3).all()
    assert np.all((d.y - y_before > 0) & (d.y - y_before <= 0.1 * 300.0))


def test_drifters_never_leave_the_water_with_noise():
    f = get_flow("scb_like")
    rng = np.random.default_rng(0)
    j, i = np.nonzero(f.water[1])
    k = rng.choice(len(j), 200)
    for rule in ("stay", "slide"):
        d = Drifters(f, f.x[i[k]], f.y[j[k]], 1, land_rule=rule, diffusivity=50.0, rng=1)
        for _ in range(40):
            d.step(900.0)
            assert f.water_at(d.x, d.y, d.layer).all()


def test_profiling_drifters_change_layer():
    f = get_flow("scb_like")
    land_below = np.argwhere(f.water[0] & f.land[1])[0]
    x = f.x[[land_below[1], 3]]
    y = f.y[[land_below[0], 3]]
    d = Drifters(f, x, y, [0, 0], t=0.0)
    legal = d.legal_actions()
    assert legal.tolist() == [[True, False, False], [True, False, True]]
    d.apply_actions([DRIFT, DOWN])
    assert d.layer.tolist() == [0, 1]
    d.apply_actions([DRIFT, DOWN])
    assert d.legal_actions()[1].tolist() == [True, True, False] and d.layer[1] == 2
    d.apply_actions([DRIFT, UP])
    assert d.layer.tolist() == [0, 1]
    with pytest.raises(ActionError, match="down is illegal for drifter 0 in layer 0"):
        d.apply_actions([DOWN, DRIFT])
    with pytest.raises(ActionError, match="expected"):
        d.apply_actions([3, 0])


def test_input_checks():
    f = get_flow("two_sink")
    with pytest.raises(ConfigError, match="drifter 0 .* not in water"):
        Drifters(f, [27e3], [5e3])
    with pytest.raises(ConfigError, match="land_rule"):
        Drifters(f, [5e3], [5e3], land_rule="bounce")
    with pytest.raises(ConfigError, match="diffusivity"):
        Drifters(f, [5e3], [5e3], diffusivity=-1.0)
    with pytest.raises(ConfigError, match="layer"):
        Drifters(f, [5e3], [5e3], layer=1)
    with pytest.raises(ConfigError, match="dt"):
        Drifters(f, [5e3], [5e3]).step(0.0)
    g = get_flow("scb_like")
    d = Drifters(g, [-118.2], [33.35], t=24 * 3600.0)
    with pytest.raises(InvalidFlowError, match="outside the field's time range"):
        d.step(600.0)
    held = Drifters(g, [-118.2], [33.35], t=24 * 3600.0, outside="hold")
    held.step(600.0)
    assert held.t == 24 * 3600.0 + 600.0
