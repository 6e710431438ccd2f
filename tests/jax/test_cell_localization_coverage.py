"""Differential tests: the JAX cell env's localization and coverage tasks against the NumPy envs.

Both envs start from the same cell (`CellEnv.reset_to` and the NumPy ``reset(options=
{"start": pose_options(env, z)})``) and take the same random actions; the JAX side runs whole
action sequences at once (jit, vmap over episodes, scan over steps). Observations must be equal
bit for bit, rewards within 1e-5 (float32 against float64), ends equal and the infos equal
(counts exactly, coverage and distances within 1e-6).
"""

from __future__ import annotations

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bounce_gym.errors import ConfigError
from bounce_gym.jax import make, pose_options

LOCALIZATION = "bounce_gym/BounceLocalization-v0"
COVERAGE = "bounce_gym/BounceCoverage-v0"
LOCALIZATION_INFO = ("candidates", "localized", "ticks_to_localize", "correct", "wrong_claim")
COVERAGE_INFO = ("coverage", "distance", "tv_distance")


def _rollout(env, params, keys):
    """A jitted ``(starts (E,), actions (E, T)) -> (first obs, reset info, per-step outputs)``
    running E episodes of T steps without automatic reset (``step_env``)."""

    def episode(start, actions):
        obs, state = env.reset_to(start, params=params)
        first = env.task.info(state.task, state.robot.z, params.task)

        def body(state, action):
            obs, state, reward, _, info = env.step_env(jax.random.PRNGKey(0), state, action,
                                                       params)
            return state, (obs, reward, info["terminated"], {k: info[k] for k in keys})

        _, steps = jax.lax.scan(body, state, actions)
        return obs, {k: first[k] for k in keys}, steps

    return jax.jit(jax.vmap(episode))


def _numpy_info(info: dict, key: str):
    return info.get(key, -1) if key == "ticks_to_localize" else info[key]


def _compare(env_id: str, options: dict, episodes: int, keys, seed: int,
             tolerance: dict[str, float], length: int | None = None) -> tuple[int, dict]:
    """Run ``episodes`` episodes of ``length`` steps (default: the registered horizon) in both
    envs; returns the number of steps compared (each episode until it terminates) and the JAX
    env's infos ((episodes, length) per key)."""
    env, params = make(env_id, **options)
    numpy_env = gym.make(env_id, **options).unwrapped
    rng = np.random.default_rng(seed)
    starts = rng.integers(0, env.model.n_cells, episodes)
    length = env.max_steps if length is None else length
    actions = rng.integers(0, env.n_actions, (episodes, length))
    first_obs, first_info, (obs, rewards, ends, infos) = jax.device_get(
        _rollout(env, params, keys)(jnp.asarray(starts), jnp.asarray(actions)))
    compared = 0
    for e in range(episodes):
        o, info = numpy_env.reset(options={"start": pose_options(env, starts[e])})
        assert np.array_equal(o, first_obs[e])
        for k in keys:
            assert np.isclose(_numpy_info(info, k), first_info[k][e],
                              rtol=0, atol=tolerance.get(k, 0)), (e, k)
        for t in range(length):
            o, r, terminated, _, info = numpy_env.step(int(actions[e, t]))
            compared += 1
            where = (e, t)
            assert np.array_equal(o, obs[e, t]), where
            assert abs(r - rewards[e, t]) <= 1e-5, (where, r, rewards[e, t])
            assert terminated == bool(ends[e, t]), where
            for k in keys:
                assert np.isclose(_numpy_info(info, k), infos[k][e, t],
                                  rtol=0, atol=tolerance.get(k, 0)), (where, k)
            if terminated:
                break
    numpy_env.close()
    return compared, infos


@pytest.mark.parametrize(("options", "episodes", "length", "least"), [
    ({}, 1200, None, 10_000),  # the registered env: Φ = {45°, 135°}, ends when localized
    ({"world": "lab_localization_b", "angles": (135.0,),  # one angle: the DFA filter
      "task_kwargs": {"filter_factory": "combinatorial", "terminate_when_localized": False}},
     60, None, 60 * 200),
    ({"world": "two_rooms", "angles": (45.0, 90.0, 135.0), "history": 2,
      "task_kwargs": {"filter_factory": "combinatorial", "tick_cost": 0.05}}, 500, 40, 2000),
])
def test_localization_matches_numpy(options, episodes, length, least):
    steps, infos = _compare(LOCALIZATION, options, episodes, LOCALIZATION_INFO,
                            seed=len(options), tolerance={}, length=length)
    assert steps >= least
    localized = (infos["ticks_to_localize"] >= 0).any(axis=1)
    assert localized.mean() > 0.5  # the claims were compared, not only their absence
    assert infos["correct"].any(axis=1)[localized].any()


@pytest.mark.parametrize(("options", "episodes"), [
    ({"backend": "cell"}, 12),  # the registered map, uniform target
    ({"backend": "cell", "world": "two_rooms", "privileged": True,
      "task_kwargs": {"cell_size": 0.5, "coverage_weight": 2.0, "distance_weight": 0.5}}, 8),
])
def test_coverage_matches_numpy(options, episodes):
    steps, infos = _compare(COVERAGE, options, episodes, COVERAGE_INFO, seed=len(options),
                            tolerance=dict.fromkeys(COVERAGE_INFO, 1e-06))
    assert steps == episodes * 500
    assert (infos["coverage"][:, -1] > infos["coverage"][:, 0]).all()


def test_belief_filter_has_no_jax_env():
    with pytest.raises(ConfigError, match="combinatorial filter only"):
        make(LOCALIZATION, task_kwargs={"filter_factory": "belief", "model_samples": 2})
