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


# -- lengths and scales within the world's (issue 36, item 6) ---------------------------------
SQUARE = 10 * 2**0.5  # the diameter of the zoo's 10 x 10 'square'


@pytest.mark.parametrize(("values", "ok"), [
    ({"step_length": SQUARE * 1e-4}, True),
    ({"step_length": SQUARE}, True),
    ({"step_length": SQUARE * 0.99e-4}, False),
    ({"step_length": SQUARE * 1.01}, False),
    ({"step_length": 1e12}, False),  # was accepted
    ({"robot_radius": 0.0}, True),
    ({"robot_radius": SQUARE * 1e-4}, True),
    ({"robot_radius": 1e-12}, False),  # hung pymunk
    ({"robot_radius": SQUARE / 2}, False),
    ({"robot_radius": SQUARE * 0.49}, True),
])
def test_lengths_lie_between_1e_4_and_1_times_the_worlds_diameter(values, ok):
    values = {"world": "square", **values}
    if ok:
        _parse(values)
        return
    field = next(iter(set(values) - {"world"}))
    with pytest.raises(ConfigError, match=rf"^{field}: expected (0 or )?a length in \[0\.00141, "
                                          r"(14\.1\]|7\.07\)) \(0\.0001 to (0\.5 times )?the "
                                          r"diameter 14\.14 of world 'square'\), got"):
        _parse(values)


@pytest.mark.parametrize(("scale", "ok"), [(0.1 / SQUARE, True), (1e7 / SQUARE, True),
                                           (0.09 / SQUARE, False), (1e-5, False),
                                           (1.1e7 / SQUARE, False), (1e12, False)])
def test_world_scale_keeps_the_world_between_10_cm_and_10_000_km(scale, ok):
    values = {"world": "square", "backend": "pymunk", "robot_radius": 1.0,
              "physics_params": {"world_scale": scale}}
    if ok:
        assert _parse(values).physics_params.world_scale == scale
        return
    with pytest.raises(ConfigError, match=r"^physics_params.world_scale: expected metres per "
                                          r"world unit in \[0\.00707, 7\.07e\+05\], so that world "
                                          r"'square' .* measures 0\.1 m to 1e\+07 m across"):
        _parse(values)


def test_the_create_2s_default_radius_is_bounded_too():
    # world_scale 1e5: the Create 2 is 1.7e-6 units across 14 units, too small for the engine
    with pytest.raises(ConfigError, match=r"^robot_radius \(None: the Create 2's 0\.17 m / "
                                          r"world_scale 100000\): expected a length"):
        _parse({"world": "square", "backend": "pymunk", "physics_params": {"world_scale": 1e5}})


@pytest.mark.parametrize(("values", "message"), [
    ({"world": "heptagon", "step_length": 0.5},
     r"^step_length: cells of side 0\.5 cut world 'heptagon' \(600 x 450\) into 900 x 1,200 "
     r"cells = 1,080,000 cells; at most 1,048,576 \(cells of side >= 0\.508\)$"),
    ({"world": "heptagon", "step_length": 1.0, "cell_bins": 360},
     r"^step_length: cells of side 1 cut world 'heptagon' \(600 x 450\) into 450 x 600 cells x "
     r"360 bins = 97,200,000 cell model states; at most 16,777,216"),
])
def test_the_cell_backends_grid_and_model_are_bounded(values, message):
    with pytest.raises(ConfigError, match=message):
        _parse({"backend": "cell", **values})
    _parse({"backend": "cell", **values, "step_length": 20.0})


@pytest.mark.parametrize(("env_id", "task_kwargs", "message"), [
    ("bounce_gym/BounceCoverage-v0", {"cell_size": 1e-3},
     r"task_kwargs\.cell_size: expected a length in \[0\.00122, 12\.2\]"),  # hung
    ("bounce_gym/BounceCoverage-v0", {"cell_size": 0.005},
     r"task_kwargs\.cell_size: cells of side 0\.005 cut world 'lab_fig1' \(10 x 7\) into "
     r"1,400 x 2,000 cells"),
    ("bounce_gym/BounceNavigation-v0", {"goal_radius": 1e12},
     r"task_kwargs\.goal_radius: expected a length in \[0\.00157, 15\.7\]"),
])
def test_task_lengths_are_bounded(env_id, task_kwargs, message):
    with pytest.raises(ConfigError, match=message):
        gym.make(env_id, task_kwargs=task_kwargs)


@pytest.mark.parametrize(("values", "message"), [
    ({"world": "heptagon"}, r"^cell_size: cells of side 1 cut world 'heptagon' \(600 x 450\) "
                            r"into 450 x 600 cells = 270,000 cells; at most 4,096"),
    ({"cell_size": 1e6}, r"^cell_size: expected a length in \[0\.00212, 21\.2\]"),
    ({"sensor_range": 22.0}, r"^sensor_range: expected cells in \(0, 21\.21\] \(the diagonal"),
    ({"world": "square", "cell_size": 10 / 64, "sensor_range": 90.0},
     r"^sensor_range: 90 cells on the 64 x 64 grid of world 'square' means checking "
     r"[\d,]+ lines of sight; at most 4,194,304"),
])
def test_the_patrol_board_is_bounded(values, message):
    with pytest.raises(ConfigError, match=message):
        pettingzoo.make("parallel", "bounce_gym/Patrol-v0", **values)


@pytest.mark.parametrize(("values", "message"), [
    ({"step_seconds": 1e300}, r"^step_seconds: expected seconds in \[2\.88, 8\.35e\+05\]"),
    ({"step_seconds": 1.0}, r"^step_seconds: expected seconds in \[2\.88, "),
    ({"diffusivity": 1e300}, r"^diffusivity: expected m²/s in \[0, 8\.82e\+04\] \(a step's "
                             r"spread"),
])
def test_the_drifters_scales_are_bounded(values, message):
    with pytest.raises(ConfigError, match=message):
        gym.make("bounce_gym/Drifter-v0", backend="continuous", **values)
    gym.make("bounce_gym/Drifter-v0", backend="continuous", step_seconds=3600.0,
             diffusivity=100.0)
