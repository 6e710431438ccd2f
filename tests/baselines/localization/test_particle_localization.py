"""Localization with a particle belief moved by the env's own dynamics (issue 24, item 4): the
task's claims, their judgement and their threshold, and the policy acting on the observation
alone."""

from __future__ import annotations

import gymnasium as gym
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.localization import ParticleLocalizationPolicy
from bounce_gym.errors import ConfigError

THRESHOLD = 0.95


def make(**task):
    return gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic",
                    max_episode_steps=80,
                    task_kwargs={"filter_factory": "particles", "particles": 1500,
                                 "claim_threshold": THRESHOLD, **task})


def run(env, policy, seed, with_info):
    """One episode: the actions, and the info of every step."""
    policy.start_options(env, seed)
    obs, info = env.reset(seed=seed)
    policy.reset(env)
    actions, infos, done = [], [], False
    while not done:
        action = policy.act(obs, info if with_info else None)
        obs, _, terminated, truncated, info = env.step(action)
        actions.append(action)
        infos.append(info)
        done = terminated or truncated
    return actions, infos


def test_claims_are_judged_never_below_the_threshold_and_the_policy_never_reads_info():
    env = make()
    policy = ParticleLocalizationPolicy.for_env(env)
    task = env.unwrapped.task
    claims = 0
    for seed in range(10_000, 10_003):
        actions, infos = run(env, policy, seed, with_info=False)  # act(obs, None)
        assert run(env, policy, seed, with_info=True)[0] == actions  # info changes nothing
        first = next((i for i, info in enumerate(infos) if info["localized"]), None)
        for info in infos[:first]:
            assert not info["correct"] and not info["wrong_claim"] and info["claims"] == 0
        if first is None:
            continue
        claims += 1
        info = infos[first]
        # the evidence held at this bump and the one before (the default claim_bumps = 2)
        assert first >= 1 and min(infos[first - 1]["belief_mass"], info["belief_mass"]) \
            >= THRESHOLD
        assert info["claims"] == 1 and info["correct"] != info["wrong_claim"]
        assert info["wrong_claims"] == int(info["wrong_claim"]) and info["withdrawn"] == 0
        if seed == 10_002:  # the last episode's state is the env's now: judge it by hand
            state = env.unwrapped.core.state
            truth = task.states.of(state.position[:1], state.heading[:1],
                                   state.contact_normal[:1])[0]
            assert infos[-1]["correct"] == (infos[-1]["claim"] == truth)
    assert claims > 0


def test_a_seed_fixes_the_claims():
    one, two = make(), make()
    policy = ParticleLocalizationPolicy.for_env(one)
    _, a = run(one, policy, 10_005, with_info=False)
    _, b = run(two, policy, 10_005, with_info=False)
    assert [(i["belief_mass"], i.get("claim")) for i in a] \
        == [(i["belief_mass"], i.get("claim")) for i in b]


def test_the_particle_filter_needs_a_supported_backend_and_bounce_steps():
    with pytest.raises(ConfigError, match="particles"):
        gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic", step_mode="tick",
                 task_kwargs={"filter_factory": "particles"})
    with pytest.raises(ConfigError, match="not supported"):
        gym.make("bounce_gym/BounceLocalization-v0",
                 task_kwargs={"filter_factory": "particles"})  # the cell backend
    with pytest.raises(ConfigError, match="particles"):
        make(particles=0)
