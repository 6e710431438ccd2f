"""The JAX cell env equals the NumPy env step for step on navigation v0 and v1.

From the same start, goal and actions (`CellEnv.reset_to` and the NumPy env's reset options,
`bounce_gym.jax.pose_options`) both give the same observations (bit for bit), rewards (the JAX
env computes in float32), terminations and infos, over more than 10⁴ steps per id: the
registered lab maps and other maps of the zoo and a generated one.
"""

from __future__ import annotations

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the ids)
from bounce_gym.jax import draws, make, pose_options
from bounce_gym.worlds.generators import random_grid

EPISODES = 128
STEPS = 64  # per episode, beyond which the JAX rollout is not compared


def _rollouts(env, params, starts, goals, actions):
    """Observations, rewards, terminations and infos of episodes (vmapped, scanned)."""
    def episode(start, goal, acts):
        obs0, state = env.reset_to(start, goal, params)

        def body(state, action):
            obs, state, reward, _, info = env.step_env(jax.random.PRNGKey(0), state, action,
                                                       params)
            return state, (obs, reward, info)

        return obs0, jax.lax.scan(body, state, acts)[1]

    out = jax.jit(jax.vmap(episode))(jnp.asarray(starts), jnp.asarray(goals),
                                     jnp.asarray(actions))
    return jax.device_get(out)  # NumPy arrays: indexed step by step below, cheaply


def _pairs(env, params, rng, v1: bool):
    if not v1:
        return rng.integers(env.model.n_cells, size=(2, EPISODES))
    starts = rng.choice(np.asarray(params.task.starts), EPISODES)
    choices, counts = np.asarray(params.task.goal_choices), np.asarray(params.task.goal_counts)
    decisions = np.asarray(params.task.decisions)
    goals = [decisions[rng.choice(choices[s, :counts[s]])] for s in starts]
    return starts, np.array(goals)


def _leaf(tree, *index):
    return jax.tree.map(lambda x: np.asarray(x[index]), tree)


def _compare(env_id, options, seed):
    env, params = make(env_id, **options)
    numpy_env = gym.make(env_id, **options)
    rng = np.random.default_rng(seed)
    v1 = env_id.endswith("v1")
    starts, goals = _pairs(env, params, rng, v1)
    actions = rng.integers(env.n_actions, size=(EPISODES, STEPS))
    first, (obs, rewards, infos) = _rollouts(env, params, starts, goals, actions)
    steps = arrivals = 0
    for e in range(EPISODES):
        reset_options = {"start": pose_options(env, starts[e]), "goal": pose_options(env, goals[e])}
        o, info = numpy_env.reset(seed=seed + e, options=reset_options)
        _assert_obs(o, _leaf(first, e))
        for t in range(STEPS):
            o, r, terminated, truncated, info = numpy_env.step(int(actions[e, t]))
            steps += 1
            _assert_obs(o, _leaf(obs, e, t))
            assert abs(r - float(rewards[e, t])) <= 1e-5 * max(1.0, abs(r)), (e, t)
            assert terminated == bool(infos["terminated"][e, t]), (e, t)
            assert truncated == bool(infos["truncated"][e, t]), (e, t)
            assert info["is_success"] == bool(infos["is_success"][e, t])
            assert info["plan_cost"] == pytest.approx(float(infos["plan_cost"][e, t]), rel=1e-6)
            assert info["ticks"] == int(infos["ticks"][e, t])
            if "ticks_to_goal" in info:
                arrivals += 1
                assert info["ticks_to_goal"] == int(infos["ticks_to_goal"][e, t])
            if v1:
                assert info["optimal_bounces"] == int(infos["optimal_bounces"][e, t])
            if terminated or truncated:
                break
    numpy_env.close()
    return steps, arrivals


def _assert_obs(numpy_obs, jax_obs):
    if isinstance(numpy_obs, dict):
        assert set(numpy_obs) == set(jax_obs)
        for key in numpy_obs:
            np.testing.assert_array_equal(numpy_obs[key], jax_obs[key])
    else:
        np.testing.assert_array_equal(numpy_obs, jax_obs)


GRID = random_grid(np.random.default_rng(7), 9, 12, 6, 3)


@pytest.mark.parametrize("env_id, options", [
    ("bounce_gym/BounceNavigation-v0", {"backend": "cell"}),
    pytest.param("bounce_gym/BounceNavigation-v0", {
        "backend": "cell", "world": "two_rooms", "angles": [45.0, 90.0, 135.0], "history": 2,
        "privileged": True, "task_kwargs": {"reward": "plan_cost"}}, marks=pytest.mark.slow),
    ("bounce_gym/BounceNavigation-v0", {"backend": "cell", "world": GRID,
                                        "task_kwargs": {"reward": "sparse", "tick_cost": 0.01}}),
    ("bounce_gym/BounceNavigation-v1", {}),
    ("bounce_gym/BounceNavigation-v1", {"world": "grid_15x15"}),
    pytest.param("bounce_gym/BounceNavigation-v1", {"world": GRID, "task_kwargs": {"draw": "any"}},
                 marks=pytest.mark.slow),
])
def test_jax_env_equals_numpy_env(env_id, options):
    steps, arrivals = _compare(env_id, options, seed=10_000)
    assert steps >= 3_400  # three cases per id (one of them slow): > 10⁴ steps compared per id
    assert arrivals > 0  # the arrival test was exercised


def test_reset_draws_and_autoreset():
    env, params = make("bounce_gym/BounceNavigation-v1")
    keys = jax.random.split(jax.random.PRNGKey(3), 256)
    obs, state = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(keys, params)
    # every drawn goal is a decision pose the start joins (optimal bounces ≥ 1)
    assert (np.asarray(state.task.optimal_bounces) >= 1).all()
    assert env.observation_space(params).contains(_leaf(obs, 0))
    step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    done_seen = False
    for t in range(50):
        actions = jnp.zeros(256, jnp.int32) + t % env.n_actions
        obs, state, reward, done, info = step(keys, state, actions, params)
        keys = jax.random.split(keys[0], 256)
        done = np.asarray(done)
        if done.any():
            done_seen = True
            # the reset episodes start afresh: no step taken yet
            assert (np.asarray(state.robot.steps)[done] == 0).all()
            assert (np.asarray(state.robot.steps)[~done] > 0).all()
    assert done_seen


@pytest.mark.parametrize("world", ["lab_navigation", GRID])
def test_v1_draws_each_goal_a_start_joins_alike(world):
    """The goal of a v1 reset is one index into the start's listed goals (O(1) per env): every
    pose lists, in order, the decision poses it joins in at least one bounce other than where
    it arrives (the NumPy task's choice), and evenly spaced uniforms draw each once."""
    env, params = make("bounce_gym/BounceNavigation-v1", world=world)
    numpy_task = gym.make("bounce_gym/BounceNavigation-v1", world=world).unwrapped.task
    reach = numpy_task.reach
    bounces = numpy_task.bounces[reach.arrival]
    listed, counts = np.asarray(params.task.goal_choices), np.asarray(params.task.goal_counts)
    others = np.arange(len(reach.decisions))
    for pose in np.asarray(params.task.starts):
        joined = np.flatnonzero((bounces[pose] > 0) & (others != reach.arrival[pose]))
        assert listed[pose, :counts[pose]].tolist() == joined.tolist()
        u = (jnp.arange(counts[pose], dtype=jnp.float32) + 0.5) / counts[pose]
        picks = np.asarray(jax.vmap(lambda x, n=int(counts[pose]): draws.index(x, n))(u))
        assert listed[pose, picks].tolist() == joined.tolist()


def test_unsupported_options_say_why():
    from bounce_gym.errors import ConfigError

    with pytest.raises(ConfigError, match="backend 'pymunk'"):
        make("bounce_gym/BounceNavigation-v0", backend="pymunk")
    with pytest.raises(ConfigError, match="actuation noise"):
        make("bounce_gym/BounceNavigation-v1",
             noise={"type": "reliable", "r": 0.8, "eps_deg": 45})
    with pytest.raises(ConfigError, match="step_mode 'tick'"):
        make("bounce_gym/Bounce-v0", backend="cell", step_mode="tick")


@pytest.mark.parametrize("world", ["lab_navigation", "configs/maps/bench_grid_14x22.yaml", GRID])
def test_v1_horizon_is_the_numpy_envs_on_every_map(world):
    """The JAX env truncates where the NumPy env's per-map horizon does (42 on the lab)."""
    numpy_env = gym.make("bounce_gym/BounceNavigation-v1", world=world)
    env, params = make("bounce_gym/BounceNavigation-v1", world=world)
    assert int(params.max_steps_in_episode) == numpy_env.spec.max_episode_steps \
        == numpy_env.unwrapped.horizon
    assert (world != "lab_navigation") or int(params.max_steps_in_episode) == 42
