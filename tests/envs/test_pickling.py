"""Envs pickle with every bounce rule on every backend the rule runs on, continue exactly like the
original after unpickling, and run in other processes: Gymnasium's `AsyncVectorEnv` and a
`ProcessPoolExecutor` give the trajectories of an in-process run."""

import copy
import pickle
from concurrent.futures import ProcessPoolExecutor

import gymnasium as gym
import numpy as np
import pytest

from bounce_gym.dynamics.rules import RULES
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv

CASES = [(rule, backend) for rule in sorted(RULES) for backend in ("kinematic", "pymunk", "cell")
         if backend != "cell" or rule == "relative"]
NOISE = {"type": "reliable", "r": 0.75, "eps_deg": 45}


def _env(kind: str, rule: str, backend: str):
    if kind == "single":
        return BounceEnv(bounce_rule=rule, backend=backend, noise=NOISE)
    return MultiBounceEnv(bounce_rule=rule, backend=backend, noise=NOISE, n_robots=3,
                          world="two_rooms", robot_radius=0.3)


def _started(kind: str, rule: str, backend: str):
    """An env reset and stepped 10 times, with the generator of its next actions."""
    env = _env(kind, rule, backend)
    env.reset(seed=5)
    actions = np.random.default_rng(6)
    _run(env, actions, 10)
    return env, actions


def _run(env, actions: np.random.Generator, steps: int) -> list:
    """Observations, rewards and robot positions of ``steps`` steps with actions drawn from
    ``actions`` (the generator travels with the env, so a copy draws the same actions)."""
    out = []
    for _ in range(steps):
        if isinstance(env, MultiBounceEnv):
            obs, reward, *_ = env.step({a: int(actions.integers(3)) for a in env.agents})
            obs, reward = np.stack(list(obs.values())), list(reward.values())
        else:
            obs, reward, *_ = env.step(int(actions.integers(3)))
        out.append((obs, reward, env.robot_state.position.copy()))
    return out


def _continue(env_and_actions: tuple, steps: int = 50) -> list:
    """Run in a worker process: continue a (pickled) env."""
    env, actions = env_and_actions
    return _run(env, actions, steps)


def _assert_same(a: list, b: list) -> None:
    assert len(a) == len(b)
    for (obs_a, rew_a, pos_a), (obs_b, rew_b, pos_b) in zip(a, b, strict=True):
        np.testing.assert_array_equal(obs_a, obs_b)
        assert rew_a == rew_b
        np.testing.assert_array_equal(pos_a, pos_b)


@pytest.mark.parametrize("kind", ["single", "multi"])
@pytest.mark.parametrize(("rule", "backend"), CASES)
def test_env_round_trip_continues_identically(kind, rule, backend):
    env, actions = _started(kind, rule, backend)
    copy, copy_actions = pickle.loads(pickle.dumps((env, actions)))
    _assert_same(_run(copy, copy_actions, 50), _run(env, actions, 50))


@pytest.mark.parametrize("kind", ["single", "multi"])
def test_process_pool_continues_every_rule_like_the_parent(kind):
    """Each started env is pickled to a worker process, which continues it: the same trajectory
    as continuing it here (pickling and determinism across processes)."""
    started = [_started(kind, rule, backend) for rule, backend in CASES]
    with ProcessPoolExecutor(max_workers=2) as pool:
        remote = list(pool.map(_continue, started))
    for (rule, backend), here, there in zip(CASES, started, remote, strict=True):
        assert len(there) == 50, (rule, backend)
        _assert_same(there, _continue(here))


def test_async_vector_env_steps_fixed_rule_envs_and_returns_them():
    """Two ``spawn`` workers receive the envs themselves (with their env functions), step them
    like a synchronous vector env does, and send them back (``get_attr``, plain pickle through
    the pipe) in a state that continues like the synchronous copies."""
    envs = [BounceEnv(bounce_rule="fixed", angles=(30.0, 60.0, 120.0), noise=NOISE)
            for _ in range(2)]
    copies = [copy.deepcopy(env) for env in envs]
    sync = gym.vector.SyncVectorEnv([lambda env=env: env for env in copies])
    vec = gym.vector.AsyncVectorEnv([lambda env=env: env for env in envs], context="spawn")
    try:
        obs, _ = vec.reset(seed=[1, 2])
        expected, _ = sync.reset(seed=[1, 2])
        np.testing.assert_array_equal(obs, expected)
        for t in range(20):
            actions = np.array([t % 3, (t + 1) % 3])
            obs, reward, *_ = vec.step(actions)
            expected, expected_reward, *_ = sync.step(actions)
            np.testing.assert_array_equal(obs, expected)
            np.testing.assert_array_equal(reward, expected_reward)
        returned = vec.get_attr("unwrapped")
    finally:
        vec.close()
        sync.close()
    for env, original in zip(returned, copies, strict=True):
        _assert_same(_run(env, np.random.default_rng(7), 50),
                     _run(original, np.random.default_rng(7), 50))
