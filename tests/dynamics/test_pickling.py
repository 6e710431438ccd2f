"""`BounceDynamics` pickles with every bounce rule on every backend the rule runs on, and an
unpickled copy continues exactly like the original (process pools and vector envs rely on it)."""

import pickle

import numpy as np
import pytest

from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.rules import RULES

#: (rule, backend) pairs: the cell backend runs Alam's relative rule only
CASES = [(rule, backend) for rule in sorted(RULES) for backend in ("kinematic", "pymunk", "cell")
         if backend != "cell" or rule == "relative"]


def _angles(rng: np.random.Generator, rule: str, backend: str, m: int) -> np.ndarray:
    if backend == "cell":  # whole 45° bins
        return np.radians(45.0 * rng.integers(1, 8, m))
    low, high = (0.1, 6.2) if rule == "relative" else (0.3, 2.8)
    return rng.uniform(low, high, m)


@pytest.mark.parametrize("rule", sorted(RULES))
def test_rules_pickle_by_name(rule):
    assert pickle.loads(pickle.dumps(RULES[rule])) is RULES[rule]


@pytest.mark.parametrize(("rule", "backend"), CASES)
def test_dynamics_round_trip_continues_identically(rule, backend):
    dyn = BounceDynamics(worlds.get("two_rooms"), 2, backend=backend, physics="ideal", rule=rule,
                         noise={"type": "reliable", "r": 0.75, "eps_deg": 45})
    dyn.reset(np.random.default_rng(3))
    params = np.random.default_rng(4)
    for _ in range(10):
        dyn.bounce(_angles(params, rule, backend, 2))
    copy, copy_params = pickle.loads(pickle.dumps((dyn, params)))
    for _ in range(50):
        ticks = dyn.bounce(_angles(params, rule, backend, 2))
        assert copy.bounce(_angles(copy_params, rule, backend, 2)) == ticks
        np.testing.assert_array_equal(copy.state.position, dyn.state.position)
        np.testing.assert_array_equal(copy.state.heading, dyn.state.heading)
        np.testing.assert_array_equal(copy.state.bumps, dyn.state.bumps)
