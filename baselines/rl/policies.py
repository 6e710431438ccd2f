"""Trained Stable-Baselines3 models as policies (`baselines.policy.Policy`).

A model file (as `baselines.rl.train` saves them, ``<algo>[-<variant>]_seed<seed>.zip``; only
trusted files, `baselines.rl.model_files`) becomes the policy that fits the env
(`experiments.runner.model_policies` picks the kind):

* Gymnasium env — `SB3Policy`: the model's deterministic action (PPO, DQN or RecurrentPPO, with
  the recurrent state carried through the episode), on the observations passed through the
  wrappers it was trained behind (frame stack, VecNormalize statistics), rebuilt from its file
  (`baselines.rl.wrappers`);
* PettingZoo parallel env — `SharedSB3Policy`: one PPO model shared by every robot, each robot's
  action **sampled** from the model's distribution for its own observation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from baselines.policy import MultiPolicy, Policy
from baselines.rl.model_files import read_model
from bounce_gym.errors import ConfigError


class SB3Policy(Policy):
    """A trained Stable-Baselines3 model as a policy (deterministic actions), behind the
    observation wrappers it was trained with."""

    def __init__(self, path: Path, env) -> None:
        from baselines.rl.wrappers import ObservationPipeline

        trained = read_model(path)
        self.pipeline = ObservationPipeline(trained.metadata.get("wrappers", {}),
                                            env.observation_space, env.action_space, path)
        self.model = trained.load(self.pipeline.observation_space, env.action_space)
        self.name = f"rl {path.stem}"

    def reset(self, env) -> None:
        import gymnasium as gym

        self.state = None
        self.start = np.ones((1,), dtype=bool)
        self.discrete = isinstance(env.action_space, gym.spaces.Discrete)

    def act(self, observation, info):
        seen = self.pipeline.first(observation) if self.start[0] else \
            self.pipeline.next(observation)
        action, self.state = self.model.predict(seen, state=self.state,
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

    def __init__(self, path: Path, env) -> None:
        trained = read_model(path)
        if trained.algo != "ppo":
            raise ConfigError(f"model {path}: a multi-robot shared policy must be a PPO model "
                              "(file name ppo[-<variant>]_seed<N>.zip, as train.py saves it)")
        agent = env.possible_agents[0]
        self.model = trained.load(env.observation_space(agent), env.action_space(agent))
        self.name = f"rl {path.stem}"

    def start_options(self, env, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        return None

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
