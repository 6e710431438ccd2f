"""A trained model's action drawn from its action distribution with a numpy ``Generator``.

The evaluation plays a trained agent's **sampled** action by default (`baselines.rl.policies`):
the stochastic policy PPO trained, not its argmax. The draws come from a generator the policy
restarts from the episode's seed (`episode_stream`), never from torch's global random state, so
an episode's actions depend on its seed alone — the same in this process, a pool worker or a Ray
actor, whatever ran before.

* Categorical distribution (``Discrete`` actions; PPO, RecurrentPPO): one uniform per row,
  inverted through the cumulative probabilities (`categorical`).
* Diagonal Gaussian (``Box`` actions): mean + std · z with z standard normal, clipped to the
  action space's bounds as Stable-Baselines3's ``predict`` clips its own samples. A model
  trained with generalized state-dependent exploration (``use_sde``) is drawn the same way from
  the Gaussian its noise gives at the current state, with fresh noise every step (as
  ``sde_sample_freq: 1``).
* DQN has no action distribution: its "sampled" action is ε-greedy at the exploration rate it
  ended training with (``exploration_final_eps``) — with probability ε a uniformly random
  action, else the greedy one — both draws from the same generator (`epsilon_greedy`).
"""

from __future__ import annotations

import numpy as np

from bounce_gym.errors import ConfigError


def episode_stream(seed: int) -> np.random.Generator:
    """The generator a trained policy samples from in the episode of ``seed``: the first child
    of the seed's ``SeedSequence``. Gymnasium seeds the env's own generator with the seed itself,
    so the policy's draws are not the very numbers the env drew the episode's start from."""
    return np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])


def categorical(probs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(k,) action indices, one per row of the (k, n) probabilities ``probs``."""
    cumulative = np.cumsum(probs, axis=1)
    draws = rng.random((len(probs), 1)) * cumulative[:, -1:]
    return np.minimum((cumulative <= draws).sum(axis=1), probs.shape[1] - 1)


def check_drawable(model, path) -> None:
    """Refuse, naming the model file at ``path``, a model whose actions `sampled_action` cannot
    draw: a distribution other than categorical or Gaussian, or squashed actions."""
    from stable_baselines3.common.distributions import (
        CategoricalDistribution,
        DiagGaussianDistribution,
        StateDependentNoiseDistribution,
    )

    dist = getattr(model.policy, "action_dist", None)
    if dist is None:  # DQN: ε-greedy
        return
    drawable = CategoricalDistribution | DiagGaussianDistribution | StateDependentNoiseDistribution
    if model.policy.squash_output or not isinstance(dist, drawable):
        raise ConfigError(f"model {path}: its actions follow a {type(dist).__name__}"
                          f"{' squashed' if model.policy.squash_output else ''}, which the "
                          "evaluation cannot sample from a seeded generator (categorical or "
                          "unsquashed Gaussian only)")


def epsilon_greedy(model, seen: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A DQN model's action for the batch of one ``seen``: uniformly random with probability
    ``exploration_final_eps``, else its greedy action."""
    greedy, _ = model.predict(seen, deterministic=True)
    return epsilon_draw(greedy, model.exploration_final_eps, model.action_space.n, rng)


def epsilon_draw(greedy, epsilon: float, n: int, rng: np.random.Generator):
    """With probability ``epsilon`` uniformly random actions of ``n`` (shaped like ``greedy``),
    else ``greedy``; both draws from ``rng``."""
    if rng.random() < epsilon:
        return rng.integers(n, size=np.shape(greedy))
    return greedy


def sampled_action(model, recurrent: bool, seen: np.ndarray, state, start: np.ndarray,
                   rng: np.random.Generator) -> tuple[np.ndarray, tuple | None]:
    """An actor-critic model's action for the batch of one ``seen``, drawn from its action
    distribution, and the recurrent state after it (``recurrent``: an LSTM policy, whose state
    ``state`` — ``None`` at the start — is carried as its ``predict`` carries it, reset where
    ``start`` is set; else ``None``)."""
    import torch
    from gymnasium import spaces
    from stable_baselines3.common.distributions import CategoricalDistribution

    policy = model.policy
    policy.set_training_mode(False)
    observation, _ = policy.obs_to_tensor(seen)
    with torch.no_grad():
        if recurrent:
            if state is None:
                zeros = np.zeros(policy.lstm_hidden_state_shape, dtype=np.float32)
                state = (zeros, zeros)
            carried = tuple(torch.tensor(s, dtype=torch.float32) for s in state)
            dist, carried = policy.get_distribution(
                observation, carried, torch.tensor(start, dtype=torch.float32))
            state = tuple(s.numpy() for s in carried)
        else:
            dist, state = policy.get_distribution(observation), None
        if isinstance(dist, CategoricalDistribution):
            return categorical(dist.distribution.probs.numpy(), rng), state
        mean = dist.distribution.mean.numpy().astype(np.float64)
        std = dist.distribution.stddev.numpy().astype(np.float64)
    space: spaces.Box = policy.action_space
    action = (mean + std * rng.standard_normal(mean.shape)).reshape((-1, *space.shape))
    return np.clip(action, space.low, space.high).astype(space.dtype), state
