"""BounceNavigation-v1's horizon: three times the longest optimal plan of the env's own map."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the ids)
from bounce_gym.envs.goal_navigation_env import HORIZON_FACTOR
from bounce_gym.envs.registration import GYM_ENVS
from bounce_gym.worlds.generators import random_grid

ENV_ID = "bounce_gym/BounceNavigation-v1"
GRID = "configs/maps/bench_grid_14x22.yaml"
GENERATED = random_grid(np.random.default_rng(7), 9, 12, 6, 3)


def _lengths(env, episodes: int) -> list[tuple[int, bool]]:
    """(steps, truncated) of episodes that always bounce by the first angle."""
    out = []
    for seed in range(episodes):
        env.reset(seed=seed)
        steps, done = 0, False
        while not done:
            _, _, terminated, truncated, _ = env.step(0)
            steps += 1
            done = terminated or truncated
        out.append((steps, truncated and not terminated))
    return out


def _longest_drawn_pair(task) -> tuple[int, int]:
    """The (start pose, goal pose) of a joined pair whose fewest bounces is the task's
    ``longest_plan``, found in the reach table row by row."""
    for start in task.starts:
        arrival = task.reach.arrival[start]
        row = task.bounces[arrival].astype(np.int64)
        row[arrival] = -1
        if row.max() == task.longest_plan:
            return int(start), int(task.reach.decisions[row.argmax()])
    raise AssertionError("no drawn pair has the longest plan")


def test_the_lab_keeps_its_horizon_of_42():
    env = gym.make(ENV_ID)
    assert HORIZON_FACTOR == 3.0
    assert env.unwrapped.task.longest_plan == 14
    assert env.unwrapped.horizon == env.spec.max_episode_steps == 42
    assert GYM_ENVS[ENV_ID][1] is None and gym.spec(ENV_ID).max_episode_steps is None


@pytest.mark.parametrize(("world", "longest"), [(GRID, 20), (GENERATED, 17)])
def test_a_map_gets_three_times_its_own_longest_plan(world, longest):
    env = gym.make(ENV_ID, world=world)
    task = env.unwrapped.task
    assert task.longest_plan == longest
    assert env.spec.max_episode_steps == math.ceil(HORIZON_FACTOR * longest)
    # the longest plan is that of a pair the env draws: started there, the env reports it
    start, goal = _longest_drawn_pair(task)
    model = task.model
    poses = {}
    for key, z in (("start", start), ("goal", goal)):
        centre, heading = model.configuration(z)
        poses[key] = {"position": [float(v) for v in centre], "heading": float(heading)}
    _, info = env.reset(seed=0, options=poses)
    assert info["optimal_bounces"] == longest
    # and no drawn pair needs more
    for seed in range(200):
        assert 1 <= env.reset(seed=seed)[1]["optimal_bounces"] <= longest


@pytest.mark.parametrize("world", [GRID, GENERATED])
def test_gym_make_with_a_world_truncates_at_the_derived_horizon(world):
    env = gym.make(ENV_ID, world=world)
    horizon = env.spec.max_episode_steps
    lengths = _lengths(env, 12)
    assert max(steps for steps, _ in lengths) == horizon
    assert all(steps == horizon for steps, truncated in lengths if truncated)
    assert any(truncated for _, truncated in lengths)


@pytest.mark.parametrize("steps", [5, 100])
def test_an_explicit_max_episode_steps_wins_shorter_or_longer(steps):
    env = gym.make(ENV_ID, max_episode_steps=steps)
    assert env.spec.max_episode_steps == steps
    lengths = _lengths(env, 4)
    assert max(n for n, _ in lengths) == steps
    # made again from its spec, the env keeps that horizon
    assert gym.make(env.spec).spec.max_episode_steps == steps
