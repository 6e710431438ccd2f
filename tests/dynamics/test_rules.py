"""Bounce rules and noise models: worked examples of Nilles et al. 2021, §3 (Def. 1,
Fig. 2) and basic invariants."""

import numpy as np
import pytest

from bounce_gym.dynamics import Exact, Interval, Reliable, make_noise, rules
from bounce_gym.errors import ConfigError

deg = np.radians


def test_specular_worked_example():
    # Def. 1: specular, α = 5π/6 gives u = π/6
    assert rules.specular_u(np.array([5 * np.pi / 6]), 0.0)[0] == pytest.approx(np.pi / 6)


@pytest.mark.parametrize(("alpha", "u"), [(150, 60), (10, 100), (60, 150)])
def test_nilles_relative_worked_examples(alpha, u):
    # Def. 1 / Fig. 2c: θ = π/2; α = 10° needs three rotations
    got = rules.nilles_relative_u(np.array([deg(alpha)]), np.array([np.pi / 2]))
    assert got[0] == pytest.approx(deg(u))


@pytest.mark.parametrize(("alpha", "u"), [(150, 40), (60, 140)])
def test_monotonic_worked_examples(alpha, u):
    # Def. 1: θ = 40°
    got = rules.monotonic_u(np.array([deg(alpha)]), np.array([deg(40)]))
    assert got[0] == pytest.approx(deg(u))


def test_monotonic_head_on_uses_theta():
    assert rules.monotonic_u(np.array([np.pi / 2]), np.array([deg(40)]))[0] == pytest.approx(deg(40))


def test_fixed_rule_is_constant_angle_to_the_wall():
    alpha = np.radians([20, 90, 170])
    np.testing.assert_allclose(rules.fixed_u(alpha, deg(30)), deg(30))


def test_heading_frame_on_a_floor_wall():
    # floor wall: inward normal +y, tangent +x. Moving down-right at 300° means α = 120°.
    normal = np.array([[0.0, 1.0]])
    assert rules.incoming_alpha(np.array([deg(300)]), normal)[0] == pytest.approx(deg(120))
    # specular reflection of 300° off the floor is 60°
    assert rules.specular(np.array([deg(300)]), normal, 0.0)[0] == pytest.approx(deg(60))
    # fixed θ = 30° leaves at 30° whatever the incoming direction
    assert rules.fixed(np.array([deg(250)]), normal, deg(30))[0] == pytest.approx(deg(30))


def test_boundary_rules_always_leave_into_free_space():
    rng = np.random.default_rng(0)
    n = 2000
    wall = rng.uniform(0, 2 * np.pi, n)
    normal = np.column_stack((np.cos(wall), np.sin(wall)))
    # incoming headings that point into the wall
    heading = wall + np.pi + rng.uniform(-np.pi / 2 + 1e-3, np.pi / 2 - 1e-3, n)
    theta = rng.uniform(0.01, np.pi - 0.01, n)
    for name in ("fixed", "specular", "monotonic", "nilles_relative"):
        out = rules.RULES[name](heading, normal, theta)
        assert (np.cos(out - wall) > 0).all(), name
        assert ((out >= 0) & (out < 2 * np.pi)).all()


def test_relative_rule_turns_ccw_from_the_current_heading():
    out = rules.relative(np.array([deg(350), deg(10)]), np.zeros((2, 2)), deg(90))
    np.testing.assert_allclose(out, deg([80, 100]))


def test_unknown_rule_and_bad_parameters_raise():
    with pytest.raises(ConfigError, match="bounce_rule: unknown rule 'bogus'"):
        rules.get_rule("bogus")
    with pytest.raises(ConfigError, match="multiple of 360"):
        rules.check_parameters("relative", [deg(90), 0.0])
    with pytest.raises(ConfigError, match="multiple of 360"):
        rules.check_parameters("relative", [2 * np.pi])
    with pytest.raises(ConfigError, match="empty"):
        rules.check_parameters("relative", [])
    with pytest.raises(ConfigError, match="between 0° and 180°"):
        rules.check_parameters("fixed", [deg(200)])
    with pytest.raises(ConfigError, match="finite"):
        rules.check_parameters("fixed", [np.nan])
    rules.check_parameters("relative", [deg(-90), deg(135)])
    rules.check_parameters("monotonic", [deg(40)])


def test_reliable_noise_statistics():
    rng = np.random.default_rng(1)
    out = Reliable(r=0.8, eps=deg(5)).sample(20000, rng)
    exact = out == 0.0
    assert exact.mean() == pytest.approx(0.8, abs=0.01)
    assert np.abs(out).max() <= deg(5)
    assert np.abs(out[~exact]).mean() == pytest.approx(deg(2.5), rel=0.05)
    np.testing.assert_array_equal(Reliable(1.0, deg(5)).sample(100, rng), 0.0)


def test_interval_and_exact_noise():
    rng = np.random.default_rng(2)
    out = Interval(-0.1, 0.3).sample(5000, rng)
    assert out.min() >= -0.1 and out.max() <= 0.3 and out.mean() == pytest.approx(0.1, abs=0.01)
    np.testing.assert_array_equal(Exact().sample(2, rng), [0.0, 0.0])


def test_make_noise_forms_and_errors():
    assert make_noise(None) == Exact() and make_noise("exact") == Exact()
    assert make_noise({"type": "reliable", "r": 0.8, "eps_deg": 5}) == Reliable(0.8, deg(5))
    assert make_noise({"type": "interval", "lo": -0.1, "hi": 0.1}) == Interval(-0.1, 0.1)
    with pytest.raises(ConfigError, match="noise.type"):
        make_noise({"type": "gaussian"})
    with pytest.raises(ConfigError, match="unknown keys"):
        make_noise({"type": "reliable", "r": 0.5, "eps": 0.1, "sigma": 1})
    with pytest.raises(ConfigError, match="needs 'r'"):
        make_noise({"type": "reliable", "eps": 0.1})
    with pytest.raises(ConfigError, match="reliability"):
        Reliable(1.5, 0.1)
    with pytest.raises(ConfigError, match="lo <= hi"):
        Interval(0.2, 0.1)
    with pytest.raises(ConfigError, match="noise"):
        make_noise(3)
