"""One declaration of the arguments serves every bouncing-robot env: shared arguments, per-env
defaults, signatures derived from it."""

from __future__ import annotations

import gymnasium as gym
import pettingzoo
import pytest

from bounce_gym.envs.arguments import validated
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv
from bounce_gym.envs.options import EnvOptions
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
            EnvOptions.model_fields["backend"].default, 8, "target_only", 0)


def test_registered_ids_accept_overrides():
    env = gym.make("bounce_gym/BounceCoverage-v0", step_length=0.5)
    assert env.unwrapped.options.step_length == 0.5
    parallel = pettingzoo.make("parallel", "bounce_gym/MultiBounce-v0", n_robots=2)
    assert parallel.unwrapped.options.n_robots == 2


def _parse(values: dict) -> EnvOptions:
    return validated(EnvOptions, values)


@pytest.mark.parametrize("history", [10_001, 10**9])
def test_history_is_bounded(history):
    # history=10**9 used to pass the options and run out of memory building the observation
    with pytest.raises(ConfigError, match=r"history: expected an integer in \[0, 10000\]"):
        _parse({"history": history})


def test_the_largest_history_is_accepted():
    assert _parse({"history": 10_000}).history == 10_000


def test_physics_defaults_per_backend():
    """pymunk runs the rigid-body model unless told otherwise; the others have only the exact
    one. Under dynamic physics the robot is a Create 2 unless sized."""
    assert _parse({}).physics == "ideal"
    assert _parse({"backend": "cell"}).physics == "ideal"
    dynamic = _parse({"backend": "pymunk"})
    assert dynamic.physics == "dynamic" and dynamic.robot_radius == 0.17
    assert dynamic.backend_options["physics"] == "dynamic"
    scaled = _parse({"backend": "pymunk", "physics_params": {"world_scale": 0.5}})
    assert scaled.robot_radius == pytest.approx(0.34)  # 0.17 m in half-metre units
    ideal = _parse({"backend": "pymunk", "physics": "ideal"})
    assert ideal.robot_radius == 0.0 and ideal.physics_params is None


def test_the_clock_bound_allows_for_turning_and_speeding_up():
    exact = _parse({"backend": "pymunk", "physics": "ideal"})
    slow_turns = _parse({"backend": "pymunk", "physics_params": {"turn_rate": 10.0}})
    assert exact.max_clock == _parse({}).max_clock
    assert slow_turns.max_clock >= exact.max_clock + 36 / 4  # a full turn: 36 s = 9 ticks


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"physics": "dynamic"}, "physics: backend 'kinematic' simulates only 'ideal'"),
    ({"backend": "cell", "physics": "dynamic"}, "physics='dynamic' needs backend='pymunk'"),
    ({"backend": "pymunk", "physics": "exact"}, r"physics: expected one of \['ideal', 'dynamic'\]"),
    ({"backend": "pymunk", "physics": "ideal", "physics_params": {"mass": 2}},
     "physics_params: only physics='dynamic'"),
    ({"physics_params": {"mass": 2}}, "physics_params: only physics='dynamic'"),
    ({"backend": "pymunk", "robot_radius": 0.0}, "robot_radius: physics='dynamic'"),
    ({"backend": "pymunk", "physics_params": {"cruise_speed": -1}}, "cruise_speed"),
    ({"backend": "pymunk", "physics_params": {"colour": 1}}, "unknown parameters"),
    ({"backend": "pymunk", "physics_params": [1, 2]}, "physics_params: expected a mapping"),
])
def test_physics_options_are_one_line_config_errors(kwargs, match):
    with pytest.raises(ConfigError, match=match) as err:
        _parse(kwargs)
    assert "\n" not in str(err.value)
