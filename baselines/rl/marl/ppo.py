"""The learner of one seed: rollouts of the teams (`baselines.rl.marl.rollout`), generalized
advantage estimation per robot (Schulman et al. 2016, Eq. 16) and PPO's clipped objective
(Schulman et al. 2017, Eq. 7 and 9), as Stable-Baselines3's PPO computes them where the two
could differ: advantages normalised per mini-batch (per robot when the robots have networks of
their own), an unclipped value loss weighted by ``vf_coef``, the entropy bonus ``ent_coef``,
Adam with ε = 1e-5, the gradient's norm clipped to ``max_grad_norm`` (per robot's networks).

With shared networks the loss is the mean over the robots' samples; with separate ones it is the
sum of each robot's mean loss, so that each robot's networks get exactly the gradient of their
own loss. Every mini-batch holds whole team-steps (every robot of a team at a step).

**Deterministic**: the weights are initialised after ``torch.manual_seed(seed)``, the actions and
the mini-batches are drawn from ``numpy.random.default_rng(seed)``, and the teams are seeded
seed, seed + 1, …: same configuration and seed, the same weights bit for bit (torch on the CPU,
with the same threads).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import torch

from baselines.rl.marl.networks import TeamNetworks, critic_size, weights
from baselines.rl.marl.rollout import Batch, Collector, team_env
from baselines.rl.marl.settings import Settings, settings
from bounce_gym.errors import ConfigError


def advantages(values: np.ndarray, rewards: np.ndarray, ends: np.ndarray,
               last_values: np.ndarray, gamma: float, lam: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """GAE advantages and returns (T, B, m) of values and rewards (T, B, m), episodes ending
    where ``ends``; ``last_values`` (B, m) are the values after the rollout."""
    out = np.empty_like(rewards)
    gae = np.zeros_like(last_values)
    next_value = last_values
    for t in range(len(rewards) - 1, -1, -1):
        live = 1.0 - ends[t]
        delta = rewards[t] + gamma * next_value * live - values[t]
        gae = delta + gamma * lam * live * gae
        out[t] = gae
        next_value = values[t]
    return out, out + values


class Learner:
    """IPPO or MAPPO (``config["algo"]``) on the teams of a validated configuration."""

    def __init__(self, config: Mapping, seed: int, monitor_keys: tuple[str, ...]) -> None:
        self.algo = config["algo"]
        self.settings: Settings = settings(config["hyperparams"], config["n_envs"])
        env = team_env(config)
        counts = env.action_space.nvec[0]
        if len(set(counts.tolist())) != 1:
            raise ConfigError(f"config.env_kwargs: {self.algo} needs every robot to have the "
                              f"same number of actions, these have {counts.tolist()}")
        m, n_obs = env.n_robots, env.single_observation_space.shape[0]
        self.agent_steps_per_iteration = self.settings.n_steps * env.num_envs * m
        self.iterations = -(-config["total_timesteps"] // self.agent_steps_per_iteration)
        self.iteration = 0
        torch.manual_seed(seed)
        self.nets = TeamNetworks(self.settings, m, n_obs,
                                 critic_size(self.algo, self.settings.share, n_obs, m),
                                 int(counts[0]))
        self.optimiser = torch.optim.Adam(self.nets.parameters(), lr=self.settings.learning_rate,
                                          eps=1e-5)
        self.rng = np.random.default_rng(seed)
        self.collector = Collector(env, self.algo, self.nets, self.settings.gamma, seed,
                                   self.rng, monitor_keys)

    @property
    def steps(self) -> int:
        """Agent-steps learned from so far."""
        return self.iteration * self.agent_steps_per_iteration

    def weights(self) -> dict[str, np.ndarray]:
        return weights(self.nets)

    def iterate(self) -> list[dict]:
        """One rollout and its updates; returns the monitor rows of the episodes that ended."""
        batch, rows = self.collector.collect(self.settings.n_steps)
        self._update(batch)
        self.iteration += 1
        return rows

    def _update(self, batch: Batch) -> None:
        s, nets = self.settings, self.nets
        with torch.no_grad():
            values = nets.values(torch.from_numpy(batch.critic)).numpy().astype(np.float64)
            last = nets.values(torch.from_numpy(batch.last_critic)).numpy().astype(np.float64)
        adv, returns = advantages(values, batch.rewards, batch.ends, last, s.gamma,
                                  s.gae_lambda)

        def flat(a: np.ndarray, dtype=torch.float32) -> torch.Tensor:
            return torch.as_tensor(a.reshape(-1, *a.shape[2:]), dtype=dtype)

        obs, critic = flat(batch.obs), flat(batch.critic)
        actions, old = flat(batch.actions, torch.int64), flat(batch.log_probs)
        adv_t, returns_t = flat(adv), flat(returns)
        axes = (0, 1) if s.share else 0
        for _ in range(s.n_epochs):
            for part in np.array_split(self.rng.permutation(len(obs)), s.n_minibatches):
                index = torch.from_numpy(part)
                log_p = torch.log_softmax(nets.logits(obs[index]), -1)
                log_prob = log_p.gather(-1, actions[index][..., None])[..., 0]
                a = adv_t[index]
                a = (a - a.mean(axes, keepdim=True)) / (a.std(axes, correction=0, keepdim=True)
                                                         + 1e-8)
                ratio = torch.exp(log_prob - old[index])
                clipped = torch.clamp(ratio, 1.0 - s.clip_range, 1.0 + s.clip_range)
                policy_loss = -torch.minimum(a * ratio, a * clipped).mean(0)
                value_loss = ((returns_t[index] - nets.values(critic[index])) ** 2).mean(0)
                entropy = -(log_p.exp() * log_p).sum(-1).mean(0)
                per_robot = policy_loss - s.ent_coef * entropy + s.vf_coef * value_loss
                loss = per_robot.mean() if s.share else per_robot.sum()
                self.optimiser.zero_grad()
                loss.backward()
                for group in nets.groups():
                    torch.nn.utils.clip_grad_norm_(group, s.max_grad_norm)
                self.optimiser.step()
