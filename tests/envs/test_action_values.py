"""Actions of every kind that are not what the action space holds raise `ActionError` in the
single- and multi-robot envs — complex values included (their imaginary part is not dropped) —
and never a raw numpy error or warning."""

import math
import warnings

import numpy as np
import pytest

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ActionError

BAD = {
    "complex": 0.5 + 3j,
    "complex with zero imaginary part": 0.5 + 0j,
    "numpy complex": np.complex128(0.5),
    "numpy complex array": np.array([0.5 + 0j]),
    "list of complex": [1 + 0j],
    "bool": True,
    "numpy bool": np.bool_(True),
    "bool array": np.array([True]),
    "string": "0.5",
    "bytes": b"1",
    "None": None,
    "NaN": math.nan,
    "inf": math.inf,
    "-inf float32": np.array([-np.inf], dtype=np.float32),
    "two values": [0.5, 0.5],
    "shape (1, 1)": np.zeros((1, 1)),
    "empty": np.zeros(0),
    "object": object(),
    "object array": np.array([0.5], dtype=object),
    "dict": {"a": 1},
    "out of range": 1.5,
}


def _envs(action_type):
    single = BounceEnv(action_type=action_type)
    single.reset(seed=0)
    multi = MultiBounceEnv(action_type=action_type, n_robots=2)
    multi.reset(seed=0)
    return [(single.step, single), (lambda a: multi.step(dict.fromkeys(multi.agents, a)),
                                    multi)]


@pytest.mark.parametrize("action_type", ["discrete", "continuous"])
@pytest.mark.parametrize("action", BAD.values(), ids=BAD.keys())
def test_bad_actions_raise_action_error_in_every_env(action_type, action):
    for step, env in _envs(action_type):
        before = env.robot_state.position.copy()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ActionError, match=r"(action|robot_\d): expected"
                                                  r"|is out(side| of range)"):
                step(action)
        np.testing.assert_array_equal(env.robot_state.position, before)


def test_complex_continuous_action_names_what_is_allowed():
    env = BounceEnv(action_type="continuous")
    env.reset(seed=0)
    with pytest.raises(ActionError, match=r"^action: expected a number in \[-1, 1\] \(real: not a "
                                          r"bool, string or complex\), got \(0\.5\+3j\)"):
        env.step(0.5 + 3j)
