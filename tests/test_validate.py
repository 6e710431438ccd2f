"""The shared checks of user-given numbers and flags: nothing is converted that is not already
a real number (or a bool, for flags)."""

import math

import numpy as np
import pytest

from bounce_gym.errors import ConfigError
from bounce_gym.validate import flag, number, numbers

NOT_NUMBERS = [True, False, np.bool_(True), "0.5", "abc", b"1", None, [1, 2], (0.5,), 1 + 2j,
               np.complex128(0.5), {"a": 1}]


@pytest.mark.parametrize("value", NOT_NUMBERS + [math.nan, math.inf, -np.inf])
def test_number_rejects_what_is_not_a_finite_real_number(value):
    with pytest.raises(ConfigError, match=r"^weight: expected a (finite )?number"):
        number("weight", value)


@pytest.mark.parametrize("value", [0, 3, 0.25, np.int8(3), np.float32(0.5), -2.0])
def test_number_accepts_ints_and_floats(value):
    assert number("weight", value) == float(value)
    assert type(number("weight", value)) is float


def test_number_minimum():
    assert number("size", 0.0, minimum=0.0) == 0.0
    with pytest.raises(ConfigError, match=r"size: expected a number > 0.0, got 0.0"):
        number("size", 0.0, minimum=0.0, strict=True)
    with pytest.raises(ConfigError, match=r"size: expected a number >= 1.0, got 0.5"):
        number("size", 0.5, minimum=1.0)


@pytest.mark.parametrize("value", [[True, 1.5], ["1", 2], [1 + 0j], np.array([1 + 0j]),
                                   np.array(["1"]), np.array([True]), [None], [[1, 2], [3]],
                                   "12", [1, math.nan], np.array([np.inf]),
                                   np.array([0.5], dtype=object).astype(complex)])
def test_numbers_rejects_any_entry_that_is_not_a_number(value):
    with pytest.raises(ConfigError, match=r"^points: expected (real|finite) numbers"):
        numbers("points", value)


def test_numbers_accepts_nested_numbers_and_real_arrays():
    np.testing.assert_array_equal(numbers("p", [[1, 2.5], [np.float32(3), np.int64(4)]]),
                                  [[1, 2.5], [3, 4]])
    assert numbers("p", np.arange(3)).dtype == np.float64
    assert numbers("p", 0.5).shape == ()


@pytest.mark.parametrize("value", [1, 0, "yes", None, 1.0, [True]])
def test_flag_accepts_only_bools(value):
    with pytest.raises(ConfigError, match=r"^observe: expected True or False"):
        flag("observe", value)
    assert flag("observe", np.bool_(False)) is False
