"""Synchronised perimeter patrols after Agmon et al. (2008), the baselines of Alam (2018,
thesis ch. 4, Table 4.1)."""

import numpy as np
import pytest

from baselines.patrolling.perimeter import perimeter_detection_times
from bounce_gym.errors import ConfigError


def _exact_mean(d, p):
    """E[T] for turn cost 1 by the linear system over (offset from the target, direction)."""
    states = [(r, s) for r in range(1, d) for s in (1, -1)]
    index = {state: k for k, state in enumerate(states)}
    a, b = np.eye(len(states)), np.ones(len(states))
    for (r, s), k in index.items():
        ahead = (r + s) % d
        if ahead:
            a[k, index[(ahead, s)]] -= p
        a[k, index[(r, -s)]] -= 1 - p
    hitting = np.linalg.solve(a, b)
    return hitting.sum() / (2 * d)  # offsets 0..d-1 uniform, offset 0 costs nothing


@pytest.mark.parametrize("m", [2, 4, 8, 16])
def test_the_deterministic_sweep_waits_half_a_spacing(m):
    d = 64 // m
    times = perimeter_detection_times(64, m, "deterministic", n_runs=20_000, seed=m)
    assert times.max() == d - 1
    assert times.mean() == pytest.approx((d - 1) / 2, rel=0.03)


@pytest.mark.parametrize("m, p", [(4, "random_walk"), (8, 0.8), (16, 0.5)])
def test_random_turns_match_the_exact_mean_hitting_time(m, p):
    times = perimeter_detection_times(64, m, p, n_runs=20_000, seed=1)
    expected = _exact_mean(64 // m, 0.5 if p == "random_walk" else p)
    assert times.mean() == pytest.approx(expected, rel=0.03)


def test_a_longer_turn_cost_slows_detection():
    quick = perimeter_detection_times(64, 4, 0.7, turn_cost=1, n_runs=10_000, seed=2)
    slow = perimeter_detection_times(64, 4, 0.7, turn_cost=4, n_runs=10_000, seed=2)
    assert slow.mean() > quick.mean() + 1


def test_same_seed_same_times():
    a = perimeter_detection_times(32, 4, 0.5, n_runs=300, seed=9)
    assert np.array_equal(a, perimeter_detection_times(32, 4, 0.5, n_runs=300, seed=9))


def test_always_turning_never_moves():
    times = perimeter_detection_times(32, 4, 0.0, n_runs=500, max_steps=40)
    assert set(np.unique(times)) == {0.0, np.inf}


def test_bad_input_raises_config_error():
    with pytest.raises(ConfigError, match="m"):
        perimeter_detection_times(64, 5, 0.5)
    with pytest.raises(ConfigError, match="p"):
        perimeter_detection_times(64, 4, 1.5)
    with pytest.raises(ConfigError, match="p"):
        perimeter_detection_times(64, 4, "maximin")
    with pytest.raises(ConfigError, match="turn_cost"):
        perimeter_detection_times(64, 4, 0.5, turn_cost=0)
