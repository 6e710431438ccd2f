"""Reference policies run in the environments: the common interface and the simple baselines.

A policy maps what the robot senses (the observation) plus the env's ``info`` to an action, one
step at a time: ``act(observation, info) -> action``. ``reset(env)`` is called after every
``env.reset`` (with the env, so a planner can read the episode's start, goal or options).
Planners (`baselines.navigation`, `baselines.coverage`, `baselines.localization`) implement the
same interface, so `evaluate.py` can run every policy on the same worlds and seeds.

`MultiPolicy` is the same for a PettingZoo parallel env (`bounce_gym.envs.MultiBounceEnv`): one
call decides the action of every live robot, ``act(observations, infos) -> {agent: action}``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np


class Policy(ABC):
    """Base class: ``reset`` is optional, ``act`` is required."""

    name = "policy"

    def reset(self, env) -> None:  # noqa: B027  (optional hook, a no-op by default)
        """Start of an episode (after ``env.reset``)."""

    @abstractmethod
    def act(self, observation: np.ndarray, info: dict):
        """The action for this step."""


class RandomAnglePolicy(Policy):
    """A uniformly random bounce angle at every step: an index into Φ (discrete actions) or a
    uniform a ∈ [-1, 1] (continuous actions)."""

    name = "random"

    def __init__(self, seed: int | None = None) -> None:
        self.rng = np.random.default_rng(seed)
        self.n = 0

    def reset(self, env) -> None:
        self.n = getattr(env.action_space, "n", 0)  # 0: continuous

    def act(self, observation, info):
        if self.n:
            return int(self.rng.integers(self.n))
        return self.rng.uniform(-1.0, 1.0, 1).astype(np.float32)


class FixedAnglePolicy(Policy):
    """Always the same bounce angle: the papers' single bounce policy φ_i."""

    def __init__(self, index: int, degrees: float) -> None:
        self.index = int(index)
        self.name = f"fixed {degrees:g}°"

    def act(self, observation, info):
        return self.index


class MultiPolicy(ABC):
    """A policy for a PettingZoo parallel env: every step, one action per live agent.

    Call order per episode: ``options = start_options(env, seed)``; ``env.reset(seed=seed,
    options=options)``; ``reset(env)``; then ``act`` every step.
    """

    name = "policy"

    def start_options(self, env, seed: int) -> dict | None:
        """Reset options the policy needs (e.g. a planner's start configuration); ``None`` lets
        the env draw its own random start."""
        return None

    def reset(self, env) -> None:  # noqa: B027  (optional hook, a no-op by default)
        """Start of an episode (after ``env.reset``)."""

    @abstractmethod
    def act(self, observations: dict, infos: dict) -> dict:
        """``{agent: action}`` for every live agent."""
