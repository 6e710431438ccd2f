"""The PettingZoo-parallel → SB3 VecEnv adapter for parameter sharing."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from pettingzoo import ParallelEnv

from baselines.rl.parallel_vec_env import ParallelToVecEnv, evaluate_shared_policy
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv


def make_env(max_cycles: int = 50, **kwargs) -> MultiBounceEnv:
    return MultiBounceEnv(world="grid_10x10", n_robots=2, task="coverage",
                          max_cycles=max_cycles, **kwargs)


def rollout(venv: ParallelToVecEnv, n: int, seed: int):
    venv.seed(seed)
    obs = [venv.reset()]
    rng = np.random.default_rng(seed)
    rews, dones = [], []
    for _ in range(n):
        actions = rng.integers(0, venv.action_space.n, size=venv.num_envs)
        o, r, d, _ = venv.step(actions)
        obs.append(o)
        rews.append(r)
        dones.append(d)
    return np.array(obs), np.array(rews), np.array(dones)


def test_contract_shapes_and_dtypes():
    venv = ParallelToVecEnv(make_env())
    assert venv.num_envs == 2
    assert venv.observation_space == make_env().observation_space("robot_0")
    obs = venv.reset()
    assert obs.shape == (2, *venv.observation_space.shape)
    assert obs.dtype == venv.observation_space.dtype
    assert all(venv.observation_space.contains(o) for o in obs)
    assert len(venv.reset_infos) == 2
    obs, rew, done, infos = venv.step(np.array([0, 1]))
    assert obs.shape == (2, *venv.observation_space.shape) and obs.dtype == np.float32
    assert rew.shape == (2,) and rew.dtype == np.float32
    assert done.shape == (2,) and done.dtype == bool
    assert isinstance(infos, list) and len(infos) == 2 and all(isinstance(i, dict) for i in infos)
    venv.close()


def test_autoreset_with_terminal_observation():
    max_cycles = 7
    venv = ParallelToVecEnv(make_env(max_cycles=max_cycles))
    venv.seed(3)
    venv.reset()
    for t in range(1, 2 * max_cycles + 1):
        obs, _, done, infos = venv.step(np.zeros(2, dtype=np.int64))
        if t % max_cycles:
            assert not done.any()
            assert all("terminal_observation" not in i for i in infos)
        else:
            assert done.all()
            for i in infos:
                term = i["terminal_observation"]
                assert term.shape == venv.observation_space.shape
                assert i["TimeLimit.truncated"] is True
            # same-step reset: the returned observation starts the next episode (clock at 0)
            assert venv.env.cycles == 0 and venv.env.agents == venv.agents
            assert obs.shape == (2, *venv.observation_space.shape)


def test_seed_determinism():
    a = rollout(ParallelToVecEnv(make_env(max_cycles=20)), 45, seed=11)
    b = rollout(ParallelToVecEnv(make_env(max_cycles=20)), 45, seed=11)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    venv = ParallelToVecEnv(make_env())
    assert venv.seed(5) == [5, 6]


def test_attr_and_method_forwarding():
    venv = ParallelToVecEnv(make_env())
    assert venv.get_attr("max_cycles") == [50, 50]
    assert venv.get_attr("max_cycles", indices=[1]) == [50]
    venv.set_attr("max_cycles", 9)
    assert venv.env.max_cycles == 9
    venv.reset()
    states = venv.env_method("state")
    assert len(states) == 2 and np.array_equal(states[0], venv.env.state())
    assert venv.env_is_wrapped(gym.Wrapper) == [False, False]
    assert venv.render_mode is None


class _Staggered(ParallelEnv):
    """robot_0 terminates after 2 steps, robot_1 after 4: tests the black-death slots."""

    metadata = {"name": "staggered"}
    possible_agents = ["robot_0", "robot_1"]
    render_mode = None

    def observation_space(self, agent):
        return spaces.Box(0.0, 10.0, (1,), np.float32)

    def action_space(self, agent):
        return spaces.Discrete(2)

    def reset(self, seed=None, options=None):
        self.agents = list(self.possible_agents)
        self.t = 0
        return {a: np.array([1.0], np.float32) for a in self.agents}, {a: {} for a in self.agents}

    def step(self, actions):
        assert set(actions) == set(self.agents)
        self.t += 1
        live = list(self.agents)
        obs = {a: np.array([1.0 + self.t], np.float32) for a in live}
        ends = {"robot_0": 2, "robot_1": 4}
        terms = {a: self.t >= ends[a] for a in live}
        self.agents = [a for a in live if not terms[a]]
        return obs, dict.fromkeys(live, 1.0), terms, dict.fromkeys(live, False), \
            {a: {} for a in live}


def test_agents_leaving_early():
    venv = ParallelToVecEnv(_Staggered())
    venv.reset()
    steps = [venv.step(np.zeros(2, dtype=np.int64)) for _ in range(4)]
    dones = np.array([s[2] for s in steps])
    assert dones.tolist() == [[False, False], [True, False], [False, False], [True, True]]
    assert steps[1][3][0]["terminal_observation"][0] == 3.0
    assert steps[1][3][0]["TimeLimit.truncated"] is False
    assert steps[2][0][0, 0] == 0.0 and steps[2][1][0] == 0.0  # black death
    assert steps[3][3][1]["terminal_observation"][0] == 5.0
    np.testing.assert_array_equal(steps[3][0], [[1.0], [1.0]])  # reset in the same step


def test_ppo_smoke_and_shared_policy_evaluation():
    pytest.importorskip("torch")
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    venv = VecMonitor(ParallelToVecEnv(make_env()))
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, seed=0, device="cpu")
    model.learn(256)
    assert model.num_timesteps >= 256
    assert len(model.ep_info_buffer) > 0  # VecMonitor saw whole episodes (50 steps each)
    env = make_env()
    returns = evaluate_shared_policy(model, env, seed=0)
    assert set(returns) == {"robot_0", "robot_1"}
    assert all(np.isfinite(r) for r in returns.values())
    assert env.agents == []
