"""The DOBSS mixed-integer program (Paruchuri et al. 2008; Alam 2018, thesis §4.4.2) against the
multiple-LP method: Table 4.3 from Table 4.2, and random games."""

import numpy as np
import pytest

from baselines.patrolling.game import stackelberg
from bounce_gym.errors import ConfigError


def test_table_4_3_by_dobss(table_4_2):
    P, Q = table_4_2
    result = stackelberg(P, Q, method="dobss")
    lp = stackelberg(P, Q, method="lp")
    assert result.value == pytest.approx(8.0, abs=1e-6)
    # v7 and v8 are both optimal responses (value 8.0); the lower index wins in both methods
    assert result.attack == lp.attack == 6
    expected = np.zeros(10)
    expected[6], expected[8] = 73 / 81, 8 / 81
    np.testing.assert_allclose(result.mixture, expected, atol=1e-4)


@pytest.mark.parametrize("seed", range(12))
def test_dobss_and_the_lps_agree_on_random_games(seed):
    rng = np.random.default_rng(seed)
    k, n = rng.integers(2, 7, size=2)
    P, Q = rng.uniform(-1, 1, (k, n)), rng.uniform(-1, 1, (k, n))
    if seed % 2:  # coarse payoffs: many tied responses
        P, Q = np.round(P * 2) / 2, np.round(Q * 2) / 2
    lp, dobss = stackelberg(P, Q), stackelberg(P, Q, method="dobss")
    assert dobss.value == pytest.approx(lp.value, abs=1e-7)
    assert dobss.attack == lp.attack
    follower = dobss.mixture @ Q
    assert follower[dobss.attack] >= follower.max() - 1e-7


def test_unknown_method_is_named(table_4_2):
    with pytest.raises(ConfigError, match="method"):
        stackelberg(*table_4_2, method="milp")
