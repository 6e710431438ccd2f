"""Reference policies run in the environments: the common interface and the simple baselines.

A policy maps what the robot senses (the observation) plus the env's ``info`` to an action, one
step at a time: ``act(observation, info) -> action``. Per episode the call order is
``options = start_options(env, seed)``; ``env.reset(seed=seed, options=options)``; ``reset(env)``;
then ``act`` every step. Planners (`baselines.navigation`, `baselines.coverage`,
`baselines.localization`) implement the same interface, so the experiment runner can run every
policy on the same worlds and seeds.

In a PettingZoo parallel env (`bounce_gym.envs.MultiBounceEnv`) one call decides the action of
every live robot: ``act(observations, infos) -> {agent: action}`` (`MultiPolicy`). The simple
baselines here, `RandomAnglePolicy` and `FixedAnglePolicy`, work in both kinds of env.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

#: Information classes: what a policy reads besides contact, clock and the task's givens (the
#: goal, and the start where the task's observation holds it). A policy declares its class in
#: ``information``; tables name every class but the first in the row's name (`labelled`).
CONTACT_AND_CLOCK = "contact and clock"
#: reads the true start configuration once, at the start of the episode
START_OBSERVED = "start observed"
#: reads the true pose (or model state) during the episode: privileged
POSE_OBSERVED = "pose observed"
INFORMATION_CLASSES = (CONTACT_AND_CLOCK, START_OBSERVED, POSE_OBSERVED)


def labelled(name: str, information: str) -> str:
    """``name`` with its information class in parentheses, unless the class is
    `CONTACT_AND_CLOCK` or the name already says it."""
    if information == CONTACT_AND_CLOCK or f"({information})" in name:
        return name
    return f"{name} ({information})"


def is_parallel_env(env) -> bool:
    """Whether ``env`` is a PettingZoo parallel env (agents keyed by name) rather than a
    Gymnasium env."""
    return hasattr(env, "possible_agents")


def episode_rng(own_seed: int | None, episode_seed: int) -> np.random.Generator:
    """The random stream a sampling policy restarts with at every episode: from its own seed if
    it has one, else from the episode's, so an episode never depends on the ones before it."""
    return np.random.default_rng(episode_seed if own_seed is None else own_seed)


class Policy(ABC):
    """Base class: ``start_options`` and ``reset`` are optional, ``act`` is required;
    ``information`` is the policy's information class (`INFORMATION_CLASSES`)."""

    name = "policy"
    information = CONTACT_AND_CLOCK

    def start_options(self, env, seed: int) -> dict | None:
        """Reset options the policy needs (e.g. a planner's start configuration); ``None`` lets
        the env draw its own random start."""
        return None

    def reset(self, env) -> None:  # noqa: B027  (optional hook, a no-op by default)
        """Start of an episode (after ``env.reset``)."""

    @abstractmethod
    def act(self, observation, info):
        """The action for this step."""


class MultiPolicy(Policy):
    """A policy for a PettingZoo parallel env: every step, one action per live agent."""

    @abstractmethod
    def act(self, observations: dict, infos: dict) -> dict:
        """``{agent: action}`` for every live agent."""


class RandomAnglePolicy(Policy):
    """A uniformly random bounce angle at every step.

    Gymnasium env: an index into Φ (discrete actions) or a uniform a ∈ [-1, 1] (continuous
    actions). Parallel env: each live robot a uniformly random index of its own Φ_i (turn
    commands, the indices past Φ_i, are never chosen).

    The random stream restarts at every episode (`start_options`): from ``seed`` if one is
    given, else from the episode's seed. Either way an episode does not depend on the episodes
    run before it.
    """

    name = "random"

    def __init__(self, seed: int | None = None) -> None:
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.n: int | dict[str, int] = 0

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_rng(self.seed, seed)
        return None

    def reset(self, env) -> None:
        if is_parallel_env(env):
            inner = env.unwrapped
            self.n = {a: len(inner.options.angles[i]) for a, i in inner.agent_index.items()}
        else:
            self.n = getattr(env.action_space, "n", 0)  # 0: continuous

    def act(self, observation, info):
        if isinstance(self.n, dict):
            return {a: int(self.rng.integers(self.n[a])) for a in observation}
        if self.n:
            return int(self.rng.integers(self.n))
        return self.rng.uniform(-1.0, 1.0, 1).astype(np.float32)


class FixedAnglePolicy(Policy):
    """Always the same bounce angle, index ``index`` of Φ (of every robot's Φ_i in a parallel
    env): the papers' single bounce policy φ_i."""

    def __init__(self, index: int, degrees: float) -> None:
        self.index = int(index)
        self.name = f"fixed {degrees:g}°"
        self.parallel = False

    def reset(self, env) -> None:
        # a parallel env's observations are a dict per robot; a goal-conditioned Gymnasium
        # env's observation is a dict too, of one robot
        self.parallel = is_parallel_env(env)

    def act(self, observation, info):
        if self.parallel:
            return dict.fromkeys(observation, self.index)
        return self.index
