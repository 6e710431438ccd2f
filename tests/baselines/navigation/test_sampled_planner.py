"""The sampled-GCM navigation planner: exact on the cell backend, blind to ``info``."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.navigation import NavigationPlanner
from baselines.navigation.sampled import SampledNavigationPlanner

ENV_ID = "bounce_gym/BounceNavigation-v0"
KWARGS = {"angles": [45, 90, 135], "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}}


def _run(env, policy, seed: int, options=None, blind: bool = False):
    obs, info = env.reset(seed=seed, options=options)
    policy.reset(env)
    actions = []
    while True:
        action = policy.act(obs, {} if blind else info)
        actions.append(action)
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return bool(info["is_success"]), actions


def test_cell_backend_reaches_every_feasible_goal_and_predicts_it():
    env = gym.make(ENV_ID, backend="cell", **KWARGS)
    roadmap = NavigationPlanner()
    planner = SampledNavigationPlanner(samples=2, cache=False)
    feasible = 0
    for seed in range(10_004, 10_009):
        env.reset(seed=seed)
        roadmap.reset(env)
        if roadmap.plan is None:
            continue
        feasible += 1
        success, _ = _run(env, planner, seed)
        assert success
        assert planner.predicted_success == pytest.approx(1.0)
    assert feasible >= 3


def test_decisions_never_read_info():
    env = gym.make(ENV_ID, backend="kinematic", **KWARGS)
    planner = SampledNavigationPlanner(samples=8, cell_size=0.5, depth=1, reach=3, cache=False)
    for seed in (10_000,):
        seen = _run(env, planner, seed)
        blind = _run(env, planner, seed, blind=True)
        assert seen == blind
        assert planner.predicted_success is not None and 0.0 <= planner.predicted_success <= 1.0


def test_particles_track_the_true_pose_without_noise():
    env = gym.make(ENV_ID, backend="kinematic", **KWARGS)
    planner = SampledNavigationPlanner(samples=8, cell_size=0.5, depth=1, reach=3, cache=False)
    obs, info = env.reset(seed=10_003)
    planner.reset(env)
    for _ in range(10):
        action = planner.act(obs, {})
        state = env.unwrapped.robot_state
        assert len(planner.point) == 1  # one exact particle: the dynamics are deterministic
        np.testing.assert_allclose(planner.point[0], state.position[0], atol=1e-9)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    assert planner.surprises == 0


def test_with_rotation_noise_the_belief_spreads_and_keeps_the_true_pose():
    """With noise every predicted pose draws its own rotation at every bump, so the belief
    holds many poses that spread as the robot's may (without the draws it could only shrink,
    to one pose, and lose the robot); it stays near the true pose (within a cell of the model)
    in most steps, and QMDP decisions (no rollouts) never read ``info``."""
    noisy = dict(KWARGS, noise={"type": "reliable", "r": 0.9, "eps_deg": 5})
    env = gym.make(ENV_ID, backend="kinematic", **noisy)
    planner = SampledNavigationPlanner(samples=8, cell_size=0.5, depth=1, reach=10,
                                       particles=16, draws=128, rollouts=False, cache=False)
    obs, info = env.reset(seed=10_001)
    planner.reset(env)
    near = spread = steps = 0
    while steps < 30:
        action = planner.act(obs, {})
        spread += len(planner.point) > 1
        position = env.unwrapped.robot_state.position[0]
        near += np.linalg.norm(planner.point - position, axis=1).min() < 0.5
        steps += 1
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    assert steps >= 5
    assert near >= 0.8 * steps and spread >= 0.5 * steps
    assert 0.0 <= planner.predicted_success <= 1.0
    seen = _run(env, planner, 10_002)
    assert seen == _run(env, planner, 10_002, blind=True)
