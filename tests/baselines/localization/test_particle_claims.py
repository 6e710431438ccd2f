"""The particle filter's claims (`bounce_gym.envs.tasks.localization.ParticleClaims`): made on
evidence, withdrawn when the belief turns against them, made again after a kidnapping, and fed
nothing but the commanded angle and the clock the robot reads."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.localization import ParticleLocalizationPolicy
from bounce_gym.dynamics import BounceDynamics


def make(particles: int = 500, steps: int = 150, **task):
    return gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic",
                    max_episode_steps=steps,
                    task_kwargs={"filter_factory": "particles", "particles": particles,
                                 "terminate_when_localized": False, **task})


def until_claim(env, policy, seed: int, limit: int = 150):
    """Reset with ``seed`` and step until the task's filter claims: the last observation and
    info, or None if no claim came within ``limit`` steps."""
    policy.start_options(env, seed)
    obs, info = env.reset(seed=seed)
    policy.reset(env)
    for _ in range(limit):
        obs, _, _, _, info = env.step(policy.act(obs, None))
        if info["localized"]:
            return obs, info
    return None


def kidnap(env, seed: int) -> int:
    """Move the robot (test only, through the env's state) to the contact a robot reaches from
    a random start drawn with ``seed``; its true decision state there."""
    base = env.unwrapped
    params = dict(base.options.robot_dynamics)
    other = BounceDynamics(params.pop("world"), 1, **params)
    placed = other.reset(np.random.default_rng(seed))
    other.drive_to_contact()
    state = base.core.state
    state.position[:], state.heading[:] = placed.position, placed.heading
    base.core.dynamics.backend.update_contacts(state, np.arange(1))
    assert state.blocked[0]
    return int(base.task.states.of(state.position[:1], state.heading[:1],
                                   state.contact_normal[:1])[0])


def test_clocks_impossible_from_the_claim_withdraw_it():
    env = make()
    policy = ParticleLocalizationPolicy.for_env(env)
    assert until_claim(env, policy, 10_000) is not None
    claims = env.unwrapped.task.filter
    belief, angle = claims.belief, np.radians(45.0)
    # the clocks the claim's particles can read after this bump (their own noise, 20 draws)
    mine = belief.states == claims.claim
    point = np.repeat(belief.position[mine], 20, axis=0)
    heading = np.repeat(belief.heading[mine], 20)
    out = belief.motion.bumps(np.array([angle]), np.zeros(len(heading), dtype=np.int64), point,
                              heading, np.random.default_rng(0), belief.max_ticks)
    possible = set(out.ticks[out.next_state >= 0].tolist())
    # a clock beyond them all (and beyond the tolerance): the claim is contradicted
    claims.update(angle, max(possible) + belief.tolerance + 2)
    assert claims.claim is None and claims.withdrawn == 1
    # a clock no drive in this world reads: depletion, the belief is drawn anew
    claims.update(angle, 10_000)
    assert belief.depletions >= 1 and (belief.previous == -1).all() and claims.claim is None


def test_a_kidnapped_robot_is_localized_again():
    env = make()
    policy = ParticleLocalizationPolicy.for_env(env)
    for seed in (10_003, 10_004):
        obs, info = until_claim(env, policy, seed)
        before = info["claim"]
        assert kidnap(env, seed + 77) != before
        withdrawn_at = relocalized_at = None
        for bump in range(1, 60):
            obs, _, _, _, info = env.step(policy.act(obs, None))
            if withdrawn_at is None and info["withdrawn"] >= 1:
                withdrawn_at = bump
            if withdrawn_at is not None and info["localized"] and info["correct"]:
                relocalized_at = bump
                break
        assert withdrawn_at is not None and withdrawn_at <= 20, seed
        assert relocalized_at is not None, seed


def test_the_filter_is_fed_only_the_commanded_angle_and_the_clock_read():
    """The task's filter keeps nothing of the env but its configuration and is updated with
    what the robot sensed only: the angle it commanded and the clock of its observation."""
    env = make(particles=300, steps=25)
    policy = ParticleLocalizationPolicy.for_env(env)
    base = env.unwrapped
    policy.start_options(env, 10_001)
    obs, _ = env.reset(seed=10_001)
    policy.reset(env)
    claims = base.task.filter
    kept = {id(v) for v in (*vars(claims).values(), *vars(claims.belief).values())}
    assert not {id(base.core), id(base.core.dynamics), id(base.core.state)} & kept
    fed = []
    update = claims.update
    claims.update = lambda angle, ticks: (fed.append((angle, ticks)), update(angle, ticks))
    angles, max_clock = np.asarray(base.options.angles[0]), int(base.options.max_clock)
    at = 1 if base.core.observes_contact else 0  # the clock's place in the observation
    sensed, done = [], False
    while not done:
        action = policy.act(obs, None)
        obs, _, terminated, truncated, _ = env.step(action)
        clock = round(float(np.asarray(obs).reshape(-1)[at]) * max_clock)
        sensed.append((float(angles[action]), clock))
        done = terminated or truncated
    assert len(fed) == len(sensed) == 25
    for (angle, ticks), (commanded, read) in zip(fed, sensed, strict=True):
        assert angle == pytest.approx(commanded) and min(ticks, max_clock) == read
