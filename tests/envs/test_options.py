"""One options table serves both environments: shared arguments, per-env defaults."""

from __future__ import annotations

import gymnasium as gym
import pettingzoo
import pytest

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv
from bounce_gym.envs.options import ARGUMENTS, parse_options
from bounce_gym.errors import ConfigError


@pytest.mark.parametrize("make, name", [
    (lambda: BounceEnv(colour="red"), "colour"),
    (lambda: BounceEnv(n_robots=2), "n_robots"),  # multi-robot arguments are not the single env's
    (lambda: BounceEnv(turn_angles=[45]), "turn_angles"),
    (lambda: gym.make("bounce_gym/Bounce-v0", colour="red"), "colour"),
    (lambda: MultiBounceEnv(colour="red"), "colour"),
    (lambda: MultiBounceAEC(colour="red"), "colour"),
])
def test_an_unknown_argument_is_a_type_error_naming_it(make, name):
    with pytest.raises(TypeError, match=f"unexpected keyword argument '{name}'"):
        make()


def test_each_env_keeps_its_defaults():
    single = BounceEnv().options
    assert (single.world.name, single.n_robots, single.robot_radius, single.robot_collisions) \
        == ("two_rooms", 1, 0.0, "ignore")
    multi = MultiBounceEnv().options
    assert (multi.world.name, multi.n_robots, multi.robot_radius, multi.robot_collisions) \
        == ("grid_15x15", 4, 0.3, "bounce")
    for options in (single, multi):
        assert (options.backend, options.cell_bins, options.corner_rule, options.history) == (
            ARGUMENTS["backend"], 8, "target_only", 0)


def test_registered_ids_accept_overrides():
    env = gym.make("bounce_gym/BounceCoverage-v0", step_length=0.5)
    assert env.unwrapped.options.step_length == 0.5
    parallel = pettingzoo.make("parallel", "bounce_gym/MultiBounce-v0", n_robots=2)
    assert parallel.unwrapped.options.n_robots == 2


@pytest.mark.parametrize("history", [10_001, 10**9])
def test_history_is_bounded(history):
    # history=10**9 used to pass the options and run out of memory building the observation
    with pytest.raises(ConfigError, match=r"history: expected an integer in \[0, 10000\]"):
        parse_options({"history": history})


def test_the_largest_history_is_accepted():
    assert parse_options({"history": 10_000}).history == 10_000
