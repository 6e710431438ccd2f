"""Dynamic physics (``backend="pymunk"``, ``physics="dynamic"``) is deterministic across
processes at the env level: a spawned interpreter — nothing inherited from this one — computes
the same trajectory digest from the seed alone, and an env pickled mid-episode and continued in
a spawned interpreter gives the digest of continuing it here. The multi-robot case is crowded, so
the solver resolves robot–robot contacts on the way."""

import hashlib
import multiprocessing
import pickle
from concurrent.futures import ProcessPoolExecutor

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv

NOISE = {"type": "reliable", "r": 0.7, "eps_deg": 20}
KINDS = ["single", "multi"]


def make(kind: str):
    if kind == "single":
        return gym.make("bounce_gym/BounceCoverage-v0", backend="pymunk", physics="dynamic",
                        noise=NOISE)
    return MultiBounceEnv(world="grid_10x10", n_robots=10, backend="pymunk", physics="dynamic",
                          task="coverage", noise=NOISE, step_mode="tick", max_cycles=10**6)


def advance(env, kind: str, rng: np.random.Generator, steps: int, digest) -> int:
    """Run ``steps`` steps of actions drawn from ``rng``, feeding observations, rewards and the
    robots' poses, clocks and bump counts into ``digest``; returns the robot contacts seen."""
    contacts = 0
    for _ in range(steps):
        if kind == "single":
            obs, reward, terminated, truncated, _ = env.step(int(rng.integers(3)))
            arrays = [obs, np.float64(reward)]
        else:
            actions = {a: int(rng.integers(env.action_space(a).n)) for a in env.agents}
            obs, rewards, *_ = env.step(actions)
            arrays = [np.stack(list(obs.values())), np.array(list(rewards.values()))]
        state = env.unwrapped.robot_state
        contacts += int(np.sum(state.contact_robot >= 0))
        for array in (*arrays, state.position, state.heading, state.clock, state.bumps):
            digest.update(np.ascontiguousarray(array).tobytes())
    return contacts


def trajectory(kind: str, seed: int, steps: int = 60) -> tuple[str, int]:
    """Digest and robot contacts of an episode built from ``seed`` alone."""
    env = make(kind)
    env.reset(seed=seed)
    digest = hashlib.sha256()
    contacts = advance(env, kind, np.random.default_rng(seed), steps, digest)
    return digest.hexdigest(), contacts


def continued(blob: bytes, steps: int = 60) -> str:
    """Digest of continuing a pickled (env, action generator) pair."""
    env, rng, kind = pickle.loads(blob)
    digest = hashlib.sha256()
    advance(env, kind, rng, steps, digest)
    return digest.hexdigest()


def started(kind: str) -> bytes:
    """An env 25 steps into an episode, pickled with its action generator."""
    env = make(kind)
    env.reset(seed=11)
    rng = np.random.default_rng(11)
    advance(env, kind, rng, 25, hashlib.sha256())
    return pickle.dumps((env, rng, kind))


@pytest.fixture(scope="module")
def spawned():
    with ProcessPoolExecutor(max_workers=1,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        yield pool


@pytest.mark.timeout(180)
@pytest.mark.parametrize("kind", KINDS)
def test_a_spawned_process_computes_the_same_digest(kind, spawned):
    here, contacts = trajectory(kind, 3)
    assert spawned.submit(trajectory, kind, 3).result(timeout=150) == (here, contacts)
    assert trajectory(kind, 4)[0] != here
    if kind == "multi":
        assert contacts > 0  # the solver met robot-robot contacts


@pytest.mark.timeout(180)
@pytest.mark.parametrize("kind", KINDS)
def test_pickled_mid_episode_continues_identically_in_a_spawned_process(kind, spawned):
    blob = started(kind)
    here = continued(blob)
    assert spawned.submit(continued, blob).result(timeout=150) == here
    assert continued(started(kind)) == here  # and pickling is itself repeatable
