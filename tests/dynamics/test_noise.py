"""Noise models take only real numbers: no bool, string, None, list, complex or non-finite value
reaches the sampling code, and each is rejected with a `ConfigError` naming the field."""

import math

import numpy as np
import pytest

from bounce_gym.dynamics.noise import Interval, Reliable, make_noise
from bounce_gym.errors import ConfigError

BAD = [True, "0.5", "abc", None, [1, 2], 1 + 2j, math.nan, math.inf]
RELIABLE = {"type": "reliable", "r": 0.5, "eps_deg": 5}
INTERVAL_RAD = {"type": "interval", "lo": -0.1, "hi": 0.1}
INTERVAL_DEG = {"type": "interval", "lo_deg": -5, "hi_deg": 5}


@pytest.mark.parametrize("value", BAD)
@pytest.mark.parametrize(("base", "key"), [
    (RELIABLE, "r"), (RELIABLE, "eps_deg"), ({"type": "reliable", "r": 0.5}, "eps"),
    (INTERVAL_RAD, "lo"), (INTERVAL_RAD, "hi"), (INTERVAL_DEG, "lo_deg"), (INTERVAL_DEG, "hi_deg"),
])
def test_bad_noise_values_raise_config_error_naming_the_field(base, key, value):
    with pytest.raises(ConfigError, match=rf"^noise\.{key}: expected a (finite )?number"):
        make_noise({**base, key: value})


@pytest.mark.parametrize("value", BAD)
def test_noise_models_built_directly_check_their_fields(value):
    with pytest.raises(ConfigError, match=r"^noise\.r: "):
        Reliable(r=value, eps=0.1)
    with pytest.raises(ConfigError, match=r"^noise\.hi: "):
        Interval(lo=-0.1, hi=value)


def test_r_is_a_probability_with_no_degrees_form():
    with pytest.raises(ConfigError, match=r"noise: unknown keys \['r_deg'\]"):
        make_noise({"type": "reliable", "r": 0.5, "eps": 0.1, "r_deg": 30})
    with pytest.raises(ConfigError, match=r"reliable needs 'r'"):
        make_noise({"type": "reliable", "r_deg": 30, "eps": 0.1})


def test_valid_noise_values_are_stored_as_floats():
    noise = make_noise({"type": "reliable", "r": np.float32(0.5), "eps_deg": 5})
    assert type(noise.r) is float and noise.r == 0.5
    assert noise.eps == float(np.radians(5))
    assert make_noise({"type": "interval", "lo": -1, "hi": 1}) == Interval(-1.0, 1.0)
