"""Localization on the sampled GCM (issue 24, item 4): the task's claims and their judgement,
and the belief policy acting on the observation alone."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.localization import AngleSwitchPolicy, BeliefLocalizationPolicy
from bounce_gym.errors import ConfigError


def run(env, policy, seed, with_info):
    obs, info = env.reset(seed=seed)
    policy.reset(env)
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(policy.act(obs, info if with_info
                                                                  else None))
        done = terminated or truncated
    return obs, info


def test_the_belief_policy_acts_on_the_observation_alone_and_claims_are_judged(tmp_path,
                                                                               monkeypatch):
    monkeypatch.setenv("BOUNCE_GYM_HOME", str(tmp_path))
    env = gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic", max_episode_steps=200,
                   task_kwargs={"filter_factory": "belief", "claim_threshold": 0.9,
                                "model_samples": 40})
    policy = BeliefLocalizationPolicy.for_env(env)
    task = env.unwrapped.task
    claims = 0
    for seed in range(10_008, 10_012):  # 10_010 claims (correctly)
        obs, info = run(env, policy, seed, with_info=False)  # act(obs, None): no info read
        # the policy's own belief is the task's (same model, same observations) once it has
        # read the last clock
        policy.act(obs, None)
        np.testing.assert_allclose(policy.filter.belief, task.filter.filter.belief)
        assert not (info["correct"] and info["wrong_claim"])
        if info["localized"]:
            claims += 1
            state = env.unwrapped.core.state
            truth = task.states.of(state.position[:1], state.heading[:1],
                                   state.contact_normal[:1])[0]
            assert info["correct"] == (info["claim"] == truth)
            assert info["belief_mass"] >= 0.9
        else:
            assert not info["correct"] and not info["wrong_claim"]
    assert claims > 0


def test_the_combinatorial_filter_on_the_cell_backend_claims_the_true_state():
    env = gym.make("bounce_gym/BounceLocalization-v0")
    policy = AngleSwitchPolicy.for_env(env)
    for seed in range(10_000, 10_005):
        _, info = run(env, policy, seed, with_info=True)
        assert info["localized"] and info["correct"] and not info["wrong_claim"]


def test_the_belief_filter_needs_bounce_steps_and_discrete_actions():
    with pytest.raises(ConfigError, match="belief"):
        gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic", step_mode="tick",
                 task_kwargs={"filter_factory": "belief"})
    with pytest.raises(ConfigError, match="claim_threshold"):
        gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic",
                 task_kwargs={"filter_factory": "belief", "claim_threshold": 0.0})
