"""The continuous-angle navigation planner and the world-reachability check: goals off the
three-angle lattice, blind to ``info``, deterministic, and the check's two answers."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.navigation.continuous import ContinuousNavigationPlanner
from baselines.navigation.motion import continuous_action, executed_angle
from baselines.navigation.reachability import noise_free, world_reachable
from baselines.navigation.sampled import SampledNavigationPlanner
from baselines.navigation.search import shortest_plan
from baselines.navigation.shots import GoalRegion, shot_intervals
from bounce_gym.dynamics.bump_table import bump_motion
from bounce_gym.envs.actions import to_angle
from bounce_gym.worlds import World

ENV_ID = "bounce_gym/BounceNavigation-v0"
ROOM = World([(0, 0), (6, 0), (6, 4), (0, 4)], name="room")
#: a start at a cell centre heading along x, and a goal whose heading, 22.5°, is 22.5° from
#: every multiple of 45°: a robot turning by 45°, 90° and 135° never heads within 10° of it
PAIR = {"goal_radius": 0.3, "heading_tolerance_deg": 10,
        "start": {"position": [1.5, 1.5], "heading": 0.0},
        "goal": {"position": [3.2, 2.4], "heading": float(np.radians(22.5))}}
#: a room split by a wall with gaps of 0.1 at both ends, which a robot of radius 0.2 cannot pass
SPLIT = World([(0, 0), (6, 0), (6, 4), (0, 4)], holes=[[(2.9, 0.1), (3.1, 0.1), (3.1, 3.9),
                                                      (2.9, 3.9)]], name="split")


def _run(env, planner, seed: int = 0, blind: bool = True):
    obs, info = env.reset(seed=seed)
    planner.reset(env)
    actions = []
    while True:
        action = planner.act(obs, {} if blind else info)
        actions.append(float(action[0]))
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return bool(info["is_success"]), actions


def test_reaches_a_goal_that_no_three_angle_sequence_reaches():
    discrete = gym.make(ENV_ID, world=ROOM, backend="kinematic", task_kwargs=PAIR)
    obs, _ = discrete.reset(seed=0)
    probe = SampledNavigationPlanner(samples=2, cell_size=0.5, depth=1, reach=3, cache=False)
    probe.reset(discrete)
    probe.act(obs, {})  # the belief: the one exact pose after the reset drive
    three = shortest_plan(probe.simulate, probe.point[0], float(probe.heading[0]),
                          probe.plan.n_actions, None, 200, 10**6, 1.0, 1.0)
    assert not three.found and three.exhausted  # proved unreachable with Φ = {45°, 90°, 135°}
    env = gym.make(ENV_ID, world=ROOM, backend="kinematic", action_type="continuous",
                   task_kwargs=PAIR)
    planner = ContinuousNavigationPlanner()
    success, actions = _run(env, planner)
    assert success and planner.predicted_success == 1.0
    assert len(actions) <= 10 and planner.surprises == 0 and planner.belief.depletions == 0


def test_decisions_never_read_info_and_repeat_with_the_seed():
    env = gym.make(ENV_ID, backend="kinematic", action_type="continuous",
                   task_kwargs={"goal_radius": 0.3, "heading_tolerance_deg": 10})
    planner = ContinuousNavigationPlanner(frontier=100, search_bumps=6)
    seen = _run(env, planner, 10_001, blind=False)
    assert seen == _run(env, planner, 10_001, blind=True)
    assert seen == _run(env, ContinuousNavigationPlanner(frontier=100, search_bumps=6), 10_001)


def test_with_rotation_noise_it_never_reads_info():
    noisy = {"type": "reliable", "r": 0.9, "eps_deg": 5}
    env = gym.make(ENV_ID, world=ROOM, backend="kinematic", action_type="continuous",
                   noise=noisy, task_kwargs=PAIR, max_episode_steps=30)
    planner = ContinuousNavigationPlanner(frontier=100, search_bumps=6, draws=64)
    seen = _run(env, planner, 3, blind=False)
    assert seen == _run(env, planner, 3, blind=True)
    assert 0.0 <= planner.predicted_success <= 1.0


def _reachable(goal_position, seed: int = 0):
    options = {"goal_radius": 0.3, "heading_tolerance_deg": 10,
               "start": {"position": [1.0, 2.0], "heading": 0.3},
               "goal": {"position": goal_position, "heading": 1.0}}
    env = gym.make(ENV_ID, world=SPLIT, backend="kinematic", action_type="continuous",
                   robot_radius=0.2, task_kwargs=options).unwrapped
    env.reset(seed=seed)
    task = env.task
    motion = bump_motion(env.cell_model(), noise_free(env.options.robot_dynamics))
    goal = GoalRegion(task.goal[0][0], float(task.goal[1][0]), task.goal_radius,
                      task.heading_tolerance)
    return world_reachable(motion, (task.start[0][0], float(task.start[1][0])), goal,
                           env.options.angle_range[0], 100, seed, walks=200)


def test_the_reachability_check_finds_the_own_room_and_not_the_other():
    near = _reachable([1.5, 1.0])
    assert near.reached and 1 <= near.first_bump <= 100
    far = _reachable([4.5, 2.0])  # behind the wall: no walk can get there
    assert not far.reached and far.first_bump == -1


def test_shot_intervals_aim_through_the_disk():
    goal = GoalRegion(np.array([3.0, 2.0]), 0.0, 0.3, np.radians(10))
    angle_range = (np.radians(45), np.radians(135))
    # from (0, 2) heading −90° the turn of 90° heads straight at the goal
    low, high = shot_intervals(np.array([[0.0, 2.0]]), np.array([-np.pi / 2]), goal,
                               angle_range)
    width = np.arcsin(0.3 / 3.0)
    np.testing.assert_allclose([low[0], high[0]], [np.pi / 2 - width, np.pi / 2 + width])
    # heading +90°: every turn of the range heads away from the goal
    low, _ = shot_intervals(np.array([[0.0, 2.0]]), np.array([np.pi / 2]), goal, angle_range)
    assert np.isnan(low[0])


@pytest.mark.parametrize("angle", [np.radians(45), 1.2345, np.radians(135)])
def test_actions_execute_the_angles_simulated(angle):
    angle_range = (np.radians(45), np.radians(135))
    action = continuous_action(np.array([angle]), angle_range)
    assert executed_angle(action, angle_range)[0] == to_angle(
        action, "continuous", np.zeros(3), angle_range)
    assert abs(executed_angle(action, angle_range)[0] - angle) < 1e-6


def test_on_dynamic_physics_a_table_hit_counts_once_the_simulator_replays_it(tmp_path,
                                                                             monkeypatch):
    """The walks read the tabulated map (a coarse one here): the goal in the start's room is
    reached, the one behind the wall is not, and a hit the simulator's replay refuses does not
    count."""
    from baselines.navigation import reachability

    env = gym.make(ENV_ID, world=SPLIT, backend="pymunk", physics="dynamic",
                   action_type="continuous", robot_radius=0.2,
                   task_kwargs={"goal_radius": 0.3, "heading_tolerance_deg": 10,
                                "start": {"position": [1.0, 2.0], "heading": 0.3}}).unwrapped
    env.reset(seed=0)
    motion = bump_motion(env.cell_model(), noise_free(env.options.robot_dynamics),
                         spacing=1.0, headings=36, cache=tmp_path)
    assert motion.table is not None
    task = env.task
    start = (task.start[0][0], float(task.start[1][0]))

    def reached(position) -> bool:
        goal = GoalRegion(np.array(position), 1.0, task.goal_radius, task.heading_tolerance)
        return world_reachable(motion, start, goal, env.options.angle_range[0], 60, 0,
                               walks=200).reached

    assert reached([1.5, 1.0]) and not reached([4.5, 2.0])
    monkeypatch.setattr(reachability, "replay_reaches", lambda *args: False)
    assert not reached([1.5, 1.0])


def _run_discrete(env, planner, seed: int, blind: bool):
    obs, info = env.reset(seed=seed)
    planner.reset(env)
    actions = []
    while True:
        action = planner.act(obs, {} if blind else info)
        actions.append(int(action))
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return bool(info["is_success"]), actions


def test_with_discrete_angles_it_searches_phi_only_and_reads_no_info():
    """On an env with Φ = {45°, 90°, 135°} the planner (the family's "search planner") returns
    indices of Φ, reaches a goal on the three-angle lattice, and ignores ``info``."""
    pair = {**PAIR, "goal": {"position": [4.5, 2.5], "heading": float(np.radians(90))}}
    env = gym.make(ENV_ID, world=ROOM, backend="kinematic", angles=[45, 90, 135],
                   task_kwargs=pair)
    planner = ContinuousNavigationPlanner(search_bumps=10)
    success, actions = _run_discrete(env, planner, 0, blind=False)
    assert planner.predicted_success in (0.0, 1.0)
    assert set(actions) <= {0, 1, 2}
    assert (success, actions) == _run_discrete(env, planner, 0, blind=True)
    assert success == (planner.predicted_success == 1.0)


@pytest.mark.parametrize(("env_kwargs", "models"), [
    ({"backend": "cell"}, ["roadmap"]),
    ({"backend": "kinematic"}, ["search"]),
    ({"backend": "pymunk", "action_type": "continuous"}, ["continuous"]),
])
def test_the_default_planner_is_the_one_that_works_on_the_motion_model(env_kwargs, models):
    from bounce_gym_experiments.families.navigation import (
        OPEN_LOOP_NAME,
        default_planner_models,
        navigation_planners,
    )

    experiment = {"env": ENV_ID, "env_kwargs": env_kwargs, "max_steps": 200}
    assert default_planner_models(experiment) == models
    if "action_type" not in env_kwargs:  # v1 (whose learners observe the pose): discrete only
        assert default_planner_models({**experiment, "env": "bounce_gym/BounceNavigation-v1"}) \
            == (["roadmap"] if env_kwargs["backend"] == "cell" else ["roadmap_pose"])
    (_, roadmap), = navigation_planners({**experiment, "planner_kwargs": {"models": ["roadmap"]}})
    assert (roadmap.name == OPEN_LOOP_NAME) == (env_kwargs["backend"] != "cell")
