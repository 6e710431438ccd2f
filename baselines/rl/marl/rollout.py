"""The experience of B teams of m robots over a rollout of ``n_steps`` steps of
`bounce_gym.envs.team_vector_env.TeamVectorEnv`, each robot's action **sampled** from its
actor's categorical distribution with the run's numpy generator.

**Autoreset** is ``NEXT_STEP``: the step that truncates the teams' episodes returns their last
observation, and the env's next step only resets them (its actions are ignored, its reward is 0).
That reset step is taken here at once and is not a transition: nothing is learned from it, and it
is not counted. A truncated episode is cut, not ended: its last reward is raised by γ·V(its last
observation) (the critic's value of what follows the cut, Pardo et al. 2018), and the advantages
do not run across it (`Batch.ends`). A terminated one (no batched task terminates today) gets no
such bootstrap.

Each finished episode gives one monitor row per robot (`Collector.collect`): its return, the
episode's length in steps and the task's outcomes that the env reports (e.g. ``coverage``), as
SB3's VecMonitor writes a row per slot of the shared PPO's VecEnv.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
import torch

from baselines.rl.action_draws import categorical
from baselines.rl.marl.networks import TeamNetworks, critic_input
from baselines.rl.monitor import MONITOR_KEYS
from bounce_gym.envs.registration import PETTINGZOO_ENVS
from bounce_gym.envs.team_vector_env import TeamVectorEnv
from bounce_gym.errors import config_errors


def team_env(config: Mapping) -> TeamVectorEnv:
    """The ``n_envs`` teams of a validated configuration's env id and ``env_kwargs`` (bad or
    unbatched options: a `ConfigError` naming ``config.env_kwargs``)."""
    with config_errors("config.env_kwargs"):
        return TeamVectorEnv(config["n_envs"], **{**PETTINGZOO_ENVS[config["env"]],
                                                  **config["env_kwargs"]})


def team_monitor_keys(config: Mapping) -> tuple[str, ...]:
    """The `MONITOR_KEYS` the task of a validated configuration reports in a step's infos (one
    step of one team, aside)."""
    probe = team_env({**config, "n_envs": 1})
    probe.reset(seed=0)
    infos = probe.step(np.zeros((1, probe.n_robots), dtype=np.int64))[4]
    return tuple(key for key in MONITOR_KEYS if key in infos)


class Batch(NamedTuple):
    """A rollout: T steps of B teams of m robots."""

    obs: np.ndarray  # (T, B, m, d) float32, what each actor saw
    critic: np.ndarray  # (T, B, m, c) float32, what each critic saw
    actions: np.ndarray  # (T, B, m) int64
    log_probs: np.ndarray  # (T, B, m) float32, under the actors that chose
    rewards: np.ndarray  # (T, B, m) float64, a truncation's bootstrap included
    ends: np.ndarray  # (T, B, m) bool, the robot's episode ended with this step
    last_critic: np.ndarray  # (B, m, c) float32, what each critic sees after the rollout


class Collector:
    """Steps the teams with the actors of ``nets`` and records what the learner needs."""

    def __init__(self, env: TeamVectorEnv, algo: str, nets: TeamNetworks, gamma: float,
                 seed: int, rng: np.random.Generator, monitor_keys: tuple[str, ...]) -> None:
        self.env, self.algo, self.nets, self.gamma = env, algo, nets, gamma
        self.rng = rng
        self.monitor_keys = monitor_keys
        self.obs, _ = env.reset(seed=seed)
        shape = self.obs.shape[:2]
        self.returns = np.zeros(shape)
        self.lengths = np.zeros(shape[0], dtype=np.int64)

    def _critic(self, obs: np.ndarray) -> np.ndarray:
        state = self.env.state() if self.algo == "mappo" else None
        return critic_input(self.algo, self.nets.share, obs, state)

    def collect(self, n_steps: int) -> tuple[Batch, list[dict]]:
        """The next ``n_steps`` transitions of every robot, and the monitor rows of the
        episodes that ended in them (in the order they ended: by step, team, robot)."""
        env, nets = self.env, self.nets
        n_teams, m = self.obs.shape[:2]
        obs = np.empty((n_steps, *self.obs.shape), dtype=np.float32)
        critic = []
        actions = np.empty((n_steps, n_teams, m), dtype=np.int64)
        log_probs = np.empty((n_steps, n_teams, m), dtype=np.float32)
        rewards = np.empty((n_steps, n_teams, m))
        ends = np.empty((n_steps, n_teams, m), dtype=bool)
        rows: list[dict] = []
        for t in range(n_steps):
            obs[t] = self.obs
            critic.append(self._critic(self.obs))
            with torch.no_grad():
                log_p = torch.log_softmax(nets.logits(torch.from_numpy(self.obs)), -1).numpy()
            probs = np.exp(log_p.reshape(n_teams * m, -1).astype(np.float64))
            actions[t] = categorical(probs, self.rng).reshape(n_teams, m)
            log_probs[t] = np.take_along_axis(log_p, actions[t][..., None], -1)[..., 0]
            self.obs, reward, terminated, truncated, infos = env.step(actions[t])
            self.returns += reward
            self.lengths += 1
            rewards[t] = reward
            ends[t] = terminated | truncated
            if not ends[t].any():
                continue
            cut = truncated & ~terminated
            if cut.any():
                with torch.no_grad():
                    final = nets.values(torch.from_numpy(self._critic(self.obs))).numpy()
                rewards[t] += self.gamma * np.where(cut, final, 0.0)
            rows += self._finished(ends[t], infos)
            # NEXT_STEP: this step only resets the teams; its actions are ignored
            self.obs, *_ = env.step(np.zeros((n_teams, m), dtype=np.int64))
        batch = Batch(obs, np.stack(critic), actions, log_probs, rewards, ends,
                      self._critic(self.obs))
        return batch, rows

    def _finished(self, ended: np.ndarray, infos: dict) -> list[dict]:
        """A monitor row per robot whose episode ended, its running return and length
        restarted."""
        rows = []
        for b, i in zip(*np.nonzero(ended), strict=True):
            outcomes = {k: np.asarray(infos[k]) for k in self.monitor_keys}  # (B,) or (B, m)
            rows.append({"r": round(float(self.returns[b, i]), 6), "l": int(self.lengths[b]),
                         **{k: (v[b] if v.ndim == 1 else v[b, i]).item()
                            for k, v in outcomes.items()}})
            self.returns[b, i] = 0.0
        self.lengths[ended.any(axis=1)] = 0
        return rows
