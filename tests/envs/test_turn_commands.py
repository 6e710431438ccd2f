"""Clock-timed turn commands of the multi-robot env (Algorithm 1's neighbour jump, Alam &
Bobadilla 2020, §4.1, is a ±Δθ turn of one robot, executed as a timed command, not a bounce:
docs/choices/multirobot.md, "A neighbour jump is a timed turn")."""

import math
import pickle

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

from bounce_gym.dynamics import BounceDynamics
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import get

GRID = dict(world="grid_10x10", n_robots=3, backend="cell", step_mode="tick",
            angles=[45, 90, 135], turn_angles=[45, -45], corner_rule="no_squeeze")


@pytest.mark.filterwarnings("ignore:reset options. unknown keys")  # the kit passes {"options": 1}
def test_parallel_api_with_turn_commands():
    parallel_api_test(MultiBounceEnv(**GRID), num_cycles=300)


@pytest.mark.parametrize("backend", ["cell", "kinematic", "pymunk"])
def test_command_tick_turns_one_robot_and_the_others_wait(backend):
    kwargs = dict(GRID, backend=backend)
    if backend != "cell":
        kwargs.update(robot_radius=0.3, physics="ideal")
    env = MultiBounceEnv(**kwargs)
    env.reset(seed=3)
    for _ in range(5):  # leave the start, so some robots are mid-drive
        env.step(dict.fromkeys(env.agents, 2))
    st = env.core.state
    pos, head = st.position.copy(), st.heading.copy()
    clock, bumps, ticks = st.clock.copy(), st.bumps.copy(), st.ticks
    _, _, _, _, infos = env.step({"robot_0": 0, "robot_1": 4, "robot_2": 1})  # robot_1: −45°
    assert np.array_equal(st.position, pos)
    turned = np.degrees(np.mod(st.heading - head, 2 * np.pi))
    np.testing.assert_allclose(turned, [0, 315, 0], atol=1e-9)
    assert np.array_equal(st.clock, clock + 1) and np.array_equal(st.bumps, bumps)
    assert st.ticks == ticks + 1 and infos["robot_0"]["step_ticks"] == 1


def test_several_robots_may_turn_in_one_command_tick():
    env = MultiBounceEnv(**GRID)
    env.reset(seed=0)
    head = env.core.state.heading.copy()
    env.step({"robot_0": 3, "robot_1": 3, "robot_2": 4})
    turned = np.degrees(np.mod(env.core.state.heading - head, 2 * np.pi))
    np.testing.assert_allclose(turned, [45, 45, 315], atol=1e-9)


def test_turning_to_face_a_wall_blocks_and_the_next_tick_is_a_bump():
    env = MultiBounceEnv(world="grid_10x10", n_robots=1, backend="cell", step_mode="tick",
                         angles=[90], turn_angles=[90, -90])
    # (0.5, 0.5) is the bottom-left free cell; heading east, a turn of −90° faces the wall
    env.reset(seed=0, options={"start": {"position": [[0.5, 0.5]], "heading": [0.0]}})
    obs, _, _, _, _ = env.step({"robot_0": 2})
    assert obs["robot_0"][0] == 1.0  # contact: pressed
    _, _, _, _, infos = env.step({"robot_0": 0})
    assert infos["robot_0"]["bumps"] == 1
    assert math.isclose(env.core.state.heading[0], 0.0, abs_tol=1e-9)  # 270° + 90°


def test_dynamics_turn_validates_and_is_deterministic_after_pickling():
    dyn = BounceDynamics(get("grid_10x10"), 2, backend="kinematic", radius=0.3,
                         robot_collisions="bounce", noise={"type": "reliable", "r": 0.5,
                                                           "eps": 0.3})
    dyn.reset(np.random.default_rng(0))
    with pytest.raises(ConfigError, match="turns: expected 2 values"):
        dyn.turn([0.1])
    with pytest.raises(ConfigError, match="finite angles or NaN"):
        dyn.turn([np.inf, np.nan])
    copy = pickle.loads(pickle.dumps(dyn))
    for d in (dyn, copy):
        for _ in range(20):
            d.turn([0.5, np.nan])
            d.tick([1.0, 2.0])
    np.testing.assert_array_equal(dyn.state.heading, copy.state.heading)
    np.testing.assert_array_equal(dyn.state.position, copy.state.position)


@pytest.mark.parametrize("kwargs, message", [
    (dict(turn_angles=[45], action_type="continuous", backend="kinematic", robot_radius=0.3),
     "need action_type='discrete'"),
    (dict(turn_angles=[30]), "not whole multiples of the 45° bins"),
    (dict(turn_angles=[45, 45]), "distinct angles"),
    (dict(turn_angles=[360]), "not multiples of 360"),
    (dict(turn_angles="45"), "a list of angles"),
    (dict(turn_angles=[float("nan")]), r"turn_angles\[0\]: expected a finite number"),
])
def test_bad_turn_angles(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        MultiBounceEnv(**{**GRID, **kwargs})


def test_aec_form_rejects_turn_commands():
    with pytest.raises(ConfigError, match="turn commands need the parallel form"):
        MultiBounceAEC(world="grid_10x10", n_robots=2, turn_angles=[45])
