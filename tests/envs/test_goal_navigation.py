"""BounceNavigation-v1: the goal-conditioned convention, its draws and its fewest bounces."""

from __future__ import annotations

import copy
import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import bounce_gym  # noqa: F401
from bounce_gym.cells.reach import UNREACHABLE, BounceReach
from bounce_gym.errors import ConfigError

ENV_ID = "bounce_gym/BounceNavigation-v1"
GRID = {"world": "configs/maps/bench_grid_14x22.yaml"}


def test_passes_the_gymnasium_and_sb3_checkers():
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(ENV_ID)
    check_env(env.unwrapped)
    sb3_check_env(env.unwrapped, warn=False)
    assert env.spec.max_episode_steps == 42
    assert isinstance(env.observation_space, gym.spaces.Dict)
    assert set(env.observation_space) == {"observation", "achieved_goal", "desired_goal"}


@pytest.mark.parametrize("kwargs", [{}, GRID, {"backend": "kinematic"}])
def test_compute_reward_is_the_step_reward(kwargs):
    env = gym.make(ENV_ID, **kwargs)
    rng = np.random.default_rng(0)
    achieved, desired, rewards, successes = [], [], [], 0
    for episode in range(60):
        obs, info = env.reset(seed=episode)
        done = False
        while not done:
            obs, reward, terminated, truncated, info = env.step(int(rng.integers(3)))
            one = env.unwrapped.compute_reward(obs["achieved_goal"], obs["desired_goal"], info)
            assert float(one) == reward
            assert info["is_success"] == terminated == (reward == 1.0)
            achieved.append(obs["achieved_goal"])
            desired.append(obs["desired_goal"])
            rewards.append(reward)
            done = terminated or truncated
        successes += terminated
    # vectorised over a batch, as the replay buffer calls it, with goals relabelled
    batch = env.unwrapped.compute_reward(np.array(achieved), np.array(desired), [{}] * len(desired))
    assert batch.shape == (len(rewards),) and np.array_equal(batch, rewards)
    relabelled = env.unwrapped.compute_reward(np.array(achieved), np.array(achieved), {})
    assert relabelled[np.array(achieved).sum(axis=1) == 2].all()
    assert 0 < successes < 60


def _fewest_bounces_by_search(env, horizon: int = 20) -> int:
    """Breadth-first search over copies of the env itself (not over the cell model)."""
    frontier = [env]
    seen = {env.unwrapped.task.achieved}
    for depth in range(1, horizon + 1):
        following = []
        for node in frontier:
            for action in range(node.action_space.n):
                child = copy.deepcopy(node)
                _, _, terminated, _, _ = child.step(action)
                if terminated:
                    return depth
                pose = child.unwrapped.task.achieved
                if pose not in seen:
                    seen.add(pose)
                    following.append(child)
        frontier = following
    return UNREACHABLE


@pytest.mark.parametrize("kwargs", [{}, GRID])
def test_optimal_bounces_is_what_a_search_of_the_env_finds(kwargs):
    env = gym.make(ENV_ID, **kwargs).unwrapped
    for seed in range(8):
        _, info = env.reset(seed=seed)
        assert info["optimal_bounces"] >= 1
        assert _fewest_bounces_by_search(env) == info["optimal_bounces"]
    # and an unreachable pair of the old draw is unreachable for the search too
    env = gym.make(ENV_ID, task_kwargs={"draw": "any"}).unwrapped
    found = 0
    for seed in range(40):
        _, info = env.reset(seed=seed)
        if info["optimal_bounces"] == UNREACHABLE:
            assert _fewest_bounces_by_search(env, horizon=16) == UNREACHABLE
            found += 1
            break
    assert found


def test_draws_only_joined_pairs_and_the_old_draw_is_an_option():
    joined = gym.make(ENV_ID)
    anything = gym.make(ENV_ID, task_kwargs={"draw": "any"})
    best = [joined.reset(seed=s)[1]["optimal_bounces"] for s in range(300)]
    old = [anything.reset(seed=s)[1]["optimal_bounces"] for s in range(300)]
    assert min(best) >= 1 and max(best) <= 14
    assert 0.5 < np.mean(np.array(old) == UNREACHABLE) < 0.9  # about 3 in 4 pairs are not joined


def test_the_roadmap_planner_reaches_every_goal_within_the_horizon():
    from baselines.navigation import NavigationPlanner

    env = gym.make(ENV_ID)
    planner = NavigationPlanner()
    ratios = []
    for seed in range(10000, 10040):
        obs, info = env.reset(seed=seed)
        planner.reset(env)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(planner.act(obs, info))
            done = terminated or truncated
        assert terminated
        ratios.append(info["bumps"] / info["optimal_bounces"])
    assert min(ratios) >= 1.0


def test_reach_table_counts_on_the_cell_model():
    env = gym.make(ENV_ID).unwrapped
    model = env.cell_model()
    reach = BounceReach(model, [math.radians(a) for a in (45, 90, 135)])
    assert np.all(model.targets[model.decode(reach.decisions)[1],
                                model.decode(reach.decisions)[0]] < 0)
    # one bounce: exactly the poses the three drives from a decision pose pass
    d = 0
    rows, poses = reach.drive_passes(reach.rotated(np.repeat(reach.decisions[d], 3), np.arange(3)))
    assert set(np.flatnonzero(reach.bounces[d] == 1)) == set(poses.tolist())


def test_fixed_start_and_goal_and_refusals():
    env = gym.make(ENV_ID).unwrapped
    task = env.task
    goal = int(task.reach.decisions[5])
    centre, heading = task.model.configuration(np.array([goal]))
    obs, info = env.reset(seed=0, options={"goal": {"position": centre[0].tolist(),
                                                    "heading": float(heading[0])}})
    assert task.goal_pose == goal and obs["desired_goal"].sum() == 2
    free = int(np.flatnonzero(task.reach.forward >= 0)[0])
    centre, heading = task.model.configuration(np.array([free]))
    with pytest.raises(ConfigError, match="not a decision pose"):
        env.reset(seed=0, options={"goal": {"position": centre[0].tolist(),
                                            "heading": float(heading[0])}})
    with pytest.raises(ConfigError, match="draw"):
        gym.make(ENV_ID, task_kwargs={"draw": "nearby"})
    with pytest.raises(ConfigError, match="half a bin"):
        gym.make(ENV_ID, task_kwargs={"heading_tolerance_deg": 30})
    with pytest.raises(ConfigError, match="discrete"):
        gym.make(ENV_ID, action_type="continuous")


def test_v0_is_unchanged_by_v1():
    env = gym.make("bounce_gym/BounceNavigation-v0", backend="cell")
    obs, info = env.reset(seed=3)
    assert obs.shape == (17,) and "optimal_bounces" not in info
