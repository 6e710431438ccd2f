"""Trained Stable-Baselines3 models as policies (`baselines.policy.Policy`).

A model file (as `baselines.rl.train` saves them, ``<algo>[-<variant>]_seed<seed>.zip``; read as
data, nothing in it unpickled, `baselines.rl.model_files`) becomes the policy that fits the env
(`bounce_gym_experiments.families.base.Family.trained_policies` picks the kind):

* Gymnasium env — `SB3Policy`: the model's action (PPO, DQN or RecurrentPPO, with the recurrent
  state carried through the episode), on the observations passed through the wrappers it was
  trained behind (frame stack, VecNormalize statistics), rebuilt from its file
  (`baselines.rl.wrappers`). By default the action is **sampled** from the model's action
  distribution with a generator restarted from the episode's seed (DQN: ε-greedy at its final
  exploration rate; `baselines.rl.action_draws`); ``deterministic=True`` gives the greedy
  action instead, the row named with `GREEDY_SUFFIX` beside the sampled one. In a deterministic
  world a greedy policy that is wrong in one state repeats the mistake there for ever;
  sampling lets it out;
* PettingZoo parallel env — `SharedSB3Policy`: one PPO model shared by every robot, each robot's
  action **sampled** from the model's distribution for its own observation (or, with
  ``deterministic=True``, its most likely action);
* the patrol game ``bounce_gym/Patrol-v0`` (`baselines.rl.patrol`) — `PatrollerSB3Policy`, the
  shared policy of a model trained with ``role: patrollers``, for the patrollers only, and
  `AdversarySB3Policy`, a model trained with ``role: adversary``, for the adversary;
  `patrol_policy` picks the one a model file was trained as.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from baselines.policy import MultiPolicy, Policy
from baselines.rl.action_draws import (
    categorical,
    check_drawable,
    episode_stream,
    epsilon_greedy,
    sampled_action,
)
from baselines.rl.model_files import read_model
from bounce_gym.errors import ConfigError

#: What the name of a greedy policy's row adds to the name of its sampled twin.
GREEDY_SUFFIX = " (greedy)"


class SB3Policy(Policy):
    """A trained Stable-Baselines3 model as a policy, behind the observation wrappers it was
    trained with: its action sampled with a generator restarted from each episode's seed
    (`baselines.rl.action_draws`), or with ``deterministic`` its greedy action."""

    def __init__(self, path: Path, env, deterministic: bool = False) -> None:
        self._load(read_model(path), env.observation_space, env.action_space, deterministic)

    def _load(self, trained, observation_space, action_space, deterministic: bool) -> None:
        import gymnasium as gym

        from baselines.rl.wrappers import ObservationPipeline

        self.pipeline = ObservationPipeline(trained.metadata.get("wrappers", {}),
                                            observation_space, action_space, trained.path)
        self.model = trained.load(self.pipeline.observation_space, action_space)
        self.deterministic = deterministic
        if not deterministic:
            check_drawable(self.model, trained.path)
        self.algo = trained.algo
        self.discrete = isinstance(action_space, gym.spaces.Discrete)
        self.rng: np.random.Generator | None = None
        self.name = f"rl {trained.path.stem}{GREEDY_SUFFIX if deterministic else ''}"

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_stream(seed)
        return None

    def reset(self, env) -> None:
        self.state = None
        self.start = np.ones((1,), dtype=bool)

    def act(self, observation, info):
        seen = self.pipeline.first(observation) if self.start[0] else \
            self.pipeline.next(observation)
        if self.deterministic:
            action, self.state = self.model.predict(seen, state=self.state,
                                                    episode_start=self.start, deterministic=True)
        elif self.rng is None:
            raise RuntimeError(f"{self.name}: start_options(env, seed) starts an episode of a "
                               "sampling policy (baselines.policy.Policy)")
        elif self.algo == "dqn":
            action = epsilon_greedy(self.model, seen, self.rng)
        else:
            action, self.state = sampled_action(self.model, self.algo == "recurrentppo", seen,
                                                self.state, self.start, self.rng)
        self.start = np.zeros((1,), dtype=bool)
        # a batch of one: the action itself
        return int(np.asarray(action).item()) if self.discrete else np.asarray(action)[0]


class SharedSB3Policy(MultiPolicy):
    """A Stable-Baselines3 PPO model as one policy shared by every robot (parameter sharing, as
    in training through `baselines.rl.parallel_vec_env.ParallelToVecEnv`).

    Every step the model gives each live robot's action distribution from its own observation
    (one batched forward pass), and each robot's action is **sampled** from it with a generator
    seeded by the episode's seed — the stochastic policy PPO trained. Its greedy (argmax) version
    is a poor baseline here: robots that sense only contact and clock and share one deterministic
    policy act alike and lock into cycles (grid_10x10, m = 2: 52 % coverage in 5000 steps where
    the sampled policy covers everything). With ``deterministic`` each robot plays its most likely
    action instead, for the row beside it (`GREEDY_SUFFIX`).
    """

    def __init__(self, path: Path, env, deterministic: bool = False) -> None:
        trained = read_model(path)
        if trained.algo != "ppo":
            raise ConfigError(f"model {path}: a multi-robot shared policy must be a PPO model "
                              "(file name ppo[-<variant>]_seed<N>.zip, as train.py saves it)")
        agent = env.possible_agents[0]
        self.model = trained.load(env.observation_space(agent), env.action_space(agent))
        self.deterministic = deterministic
        self.name = f"rl {path.stem}{GREEDY_SUFFIX if deterministic else ''}"

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
        actions = probs.argmax(axis=1) if self.deterministic else categorical(probs, self.rng)
        return {a: int(act) for a, act in zip(live, actions, strict=True)}


def _role(path: Path):
    """The model file at ``path`` and the patrol-game role it was trained as (None for a model
    of another env)."""
    from baselines.rl.patrol import PATROL_ID

    trained = read_model(path)
    config = trained.metadata.get("config", {})
    return trained, config.get("role") if config.get("env") == PATROL_ID else None


def _patrol_model(path: Path, role: str):
    trained, found = _role(path)
    if found != role:
        raise ConfigError(f"model {path}: trained as {found or 'no side of the patrol game'}, "
                          f"not as its {role} (config.role of train.py)")
    return trained


class PatrollerSB3Policy(SharedSB3Policy):
    """A model trained with ``role: patrollers`` (`baselines.rl.patrol.PatrollersEnv`) as the
    patrollers' policy in a Patrol-v0 parallel env: the shared policy, its actions sampled, for
    every patroller in the observations; the adversary is not its business."""

    def __init__(self, path: Path, env) -> None:
        _patrol_model(path, "patrollers")
        super().__init__(path, env)

    def act(self, observations, infos):
        from baselines.rl.patrol import ADVERSARY

        return super().act({a: o for a, o in observations.items() if a != ADVERSARY}, infos)


class AdversarySB3Policy(SB3Policy):
    """A model trained with ``role: adversary`` (`baselines.rl.patrol.AdversaryEnv`) as the
    adversary's policy in a Patrol-v0 parallel env: ``act(observation, info)`` takes the
    adversary's own observation and gives its sampled action (with ``deterministic``, its greedy
    one), as `SB3Policy` does."""

    def __init__(self, path: Path, env, deterministic: bool = False) -> None:
        from baselines.rl.patrol import ADVERSARY

        self._load(_patrol_model(path, "adversary"), env.observation_space(ADVERSARY),
                   env.action_space(ADVERSARY), deterministic)


def patrol_policy(path: Path, env, deterministic: bool = False
                  ) -> PatrollerSB3Policy | AdversarySB3Policy:
    """The policy of the side of the patrol game the model at ``path`` was trained as; a
    trained adversary plays its greedy action with ``deterministic`` (the patrollers always
    sample: the Stackelberg adversary is told the chain their distribution induces,
    `baselines.patrolling.policies.LearnedPatrollers`)."""
    _, role = _role(path)
    if role == "patrollers":
        return PatrollerSB3Policy(path, env)
    if role == "adversary":
        return AdversarySB3Policy(path, env, deterministic)
    raise ConfigError(f"model {path}: not trained on the patrol game (config.role of train.py)")
