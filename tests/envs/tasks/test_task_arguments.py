"""Every task keyword that takes a number or a flag rejects anything else with a `ConfigError`
naming the keyword, when the env is built — nothing is converted (True is not 1, "0.5" is not
0.5) and no raw ValueError/TypeError escapes."""

import math

import numpy as np
import pytest

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError

NOT_NUMBERS = [True, "0.5", "a", None, math.nan, math.inf, [1, 2], 1 + 2j]
NOT_FLAGS = [1, 0, "yes", None, math.nan, [True], 1 + 2j]
NAV = {"world": "lab_navigation", "task": "navigation"}

#: (env class, env arguments, keyword, what may also be None)
NUMBER_KEYWORDS = [
    (BounceEnv, NAV, "goal_radius", True),
    (BounceEnv, NAV, "heading_tolerance_deg", False),
    (BounceEnv, NAV, "w1", False),
    (BounceEnv, NAV, "w2", False),
    (BounceEnv, NAV, "goal_bonus", True),
    (BounceEnv, NAV, "tick_cost", False),
    (BounceEnv, NAV, "gamma", True),
    (BounceEnv, {"task": "localization"}, "tick_cost", False),
    (BounceEnv, {"task": "coverage"}, "cell_size", True),
    (BounceEnv, {"task": "coverage"}, "coverage_weight", False),
    (BounceEnv, {"task": "coverage"}, "distance_weight", False),
    (MultiBounceEnv, {"task": "monitoring"}, "contact_penalty", False),
]
FLAG_KEYWORDS = [
    (BounceEnv, NAV, "observe_task"),
    (BounceEnv, {"task": "localization"}, "terminate_when_localized"),
]


@pytest.mark.parametrize("value", NOT_NUMBERS, ids=repr)
@pytest.mark.parametrize(("env", "kwargs", "keyword", "none_ok"), NUMBER_KEYWORDS,
                         ids=[k[2] for k in NUMBER_KEYWORDS])
def test_number_keywords_take_only_finite_numbers(env, kwargs, keyword, none_ok, value):
    if value is None and none_ok:
        env(**kwargs, task_kwargs={keyword: None})  # None: the default
        return
    with pytest.raises(ConfigError, match=rf"^{keyword}: expected a (finite )?number"):
        env(**kwargs, task_kwargs={keyword: value})


@pytest.mark.parametrize("value", NOT_FLAGS, ids=repr)
@pytest.mark.parametrize(("env", "kwargs", "keyword"), FLAG_KEYWORDS,
                         ids=[k[2] for k in FLAG_KEYWORDS])
def test_flag_keywords_take_only_bools(env, kwargs, keyword, value):
    with pytest.raises(ConfigError, match=rf"^{keyword}: expected True or False"):
        env(**kwargs, task_kwargs={keyword: value})


@pytest.mark.parametrize("bad", [True, "1.5", None, math.nan, 1 + 0j, [1, 2]], ids=repr)
@pytest.mark.parametrize("part", ["position", "heading"])
def test_navigation_poses_take_only_numbers(part, bad):
    pose = {"position": [1.5, 1.5], "heading": 0.0}
    pose[part] = [bad, 1.5] if part == "position" else bad
    with pytest.raises(ConfigError, match=r"options\['start'\]"):
        BounceEnv(**NAV, task_kwargs={"start": pose})
    env = BounceEnv(**NAV)
    with pytest.raises(ConfigError, match=r"options\['goal'\]"):
        env.reset(seed=0, options={"goal": pose})


@pytest.mark.parametrize("bad", [True, "0.1", None, math.nan, 1 + 0j], ids=repr)
def test_coverage_target_takes_only_numbers(bad):
    shape = BounceEnv(task="coverage").task.free.shape
    target = np.zeros(shape, dtype=object)
    target[0, 0] = bad
    with pytest.raises(ConfigError, match=r"^coverage target: expected (real|finite) numbers"):
        BounceEnv(task="coverage", task_kwargs={"target": target.tolist()})
    with pytest.raises(ConfigError, match=r"^coverage target: expected (real|finite) numbers"):
        BounceEnv(task="coverage", task_kwargs={"target": np.full(shape, 1 + 0j)})


@pytest.mark.parametrize("regions", [True, 3.0, "abc", [[[0, 0], [1, 0], [True, 1]]],
                                     [[[0, 0], [1, 0], ["1", 1]]], [[[0, 0], [1, 0]]],
                                     [[[0, 0], [1, 0], [math.nan, 1]]], [[0, 1, 2]]], ids=repr)
def test_monitoring_regions_take_only_polygons_of_numbers(regions):
    with pytest.raises(ConfigError, match=r"^regions(\[0\])?: expected"):
        MultiBounceEnv(task="monitoring", n_robots=1, task_kwargs={"regions": regions})


def test_valid_task_numbers_are_stored_as_floats():
    env = BounceEnv(**NAV, task_kwargs={"w1": 1, "w2": np.int64(50), "goal_bonus": 7,
                                        "observe_task": np.bool_(False)})
    task = env.task
    assert (task.w1, task.w2, task.goal_bonus, task.observe_task) == (1.0, 50.0, 7.0, False)
    assert type(task.w2) is float and type(task.observe_task) is bool
