"""Trained Stable-Baselines3 models as policies (`baselines.policy.Policy`).

`sb3_policies` loads every model file of a folder (as `baselines.rl.train` saves them,
``<algo>_seed<seed>.zip``) as the policy that fits the env:

* Gymnasium env — `SB3Policy`: the model's deterministic action (PPO, DQN or RecurrentPPO, with
  the recurrent state carried through the episode);
* PettingZoo parallel env — `SharedSB3Policy`: one PPO model shared by every robot, each robot's
  action **sampled** from the model's distribution for its own observation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from baselines.policy import MultiPolicy, Policy
from bounce_gym.errors import ConfigError


def sb3_policies(folder: Path, parallel: bool) -> list[Policy]:
    """One policy per model file in ``folder`` (none if it does not exist): `SharedSB3Policy`
    for a parallel env, `SB3Policy` otherwise."""
    kind = SharedSB3Policy if parallel else SB3Policy
    return [kind(path) for path in sorted(folder.glob("*.zip"))] if folder.is_dir() else []


class SB3Policy(Policy):
    """A trained Stable-Baselines3 model as a policy (deterministic actions)."""

    def __init__(self, path: Path) -> None:
        from sb3_contrib import RecurrentPPO
        from stable_baselines3 import DQN, PPO

        algos = {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}
        algo = path.stem.split("_")[0].lower()
        if algo not in algos:
            raise ConfigError(f"model {path}: name must start with one of {sorted(algos)}")
        self.model = algos[algo].load(path, device="cpu")
        self.name = f"rl {path.stem}"
        self.recurrent = algo == "recurrentppo"

    def reset(self, env) -> None:
        import gymnasium as gym

        self.state = None
        self.start = np.ones((1,), dtype=bool)
        self.discrete = isinstance(env.action_space, gym.spaces.Discrete)

    def act(self, observation, info):
        action, self.state = self.model.predict(observation, state=self.state,
                                                episode_start=self.start, deterministic=True)
        self.start = np.zeros((1,), dtype=bool)
        return int(np.asarray(action).item()) if self.discrete else np.asarray(action)


class SharedSB3Policy(MultiPolicy):
    """A Stable-Baselines3 PPO model as one policy shared by every robot (parameter sharing, as
    in training through `baselines.rl.parallel_vec_env.ParallelToVecEnv`).

    Every step the model gives each live robot's action distribution from its own observation
    (one batched forward pass), and each robot's action is **sampled** from it with a generator
    seeded by the episode's seed — the stochastic policy PPO trained. Its greedy (argmax) version
    is a poor baseline here: robots that sense only contact and clock and share one deterministic
    policy act alike and lock into cycles (grid_10x10, m = 2: 52 % coverage in 5000 steps where
    the sampled policy covers everything).
    """

    def __init__(self, path: Path) -> None:
        from stable_baselines3 import PPO

        if not path.stem.lower().startswith("ppo"):
            raise ConfigError(f"model {path}: a multi-robot shared policy must be a PPO model "
                              "(file name ppo_*.zip, as train.py saves it)")
        self.model = PPO.load(path, device="cpu")
        self.path = path
        self.name = f"rl {path.stem}"

    def start_options(self, env, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        return None

    def reset(self, env) -> None:
        agent = env.possible_agents[0]
        obs_space, act_space = env.observation_space(agent), env.action_space(agent)
        if self.model.observation_space != obs_space or self.model.action_space != act_space:
            raise ConfigError(
                f"rl_models: {self.path} was trained for observations "
                f"{self.model.observation_space} and actions {self.model.action_space}, but this "
                f"experiment's robots have {obs_space} and {act_space} (train with the same "
                "env_kwargs)")

    def act(self, observations, infos):
        import torch

        live = list(observations)
        batch, _ = self.model.policy.obs_to_tensor(np.stack([observations[a] for a in live]))
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # a batch of m tiny rows: intra-op threads only add overhead
        try:
            with torch.no_grad():
                probs = self.model.policy.get_distribution(batch).distribution.probs.numpy()
        finally:
            torch.set_num_threads(threads)
        cumulative = np.cumsum(probs, axis=1)
        draws = self.rng.random((len(live), 1)) * cumulative[:, -1:]
        actions = np.minimum((cumulative <= draws).sum(axis=1), probs.shape[1] - 1)
        return {a: int(act) for a, act in zip(live, actions, strict=True)}
