"""Choosing bounce angles to localize on the sampled GCM, from contact and clock only."""

from __future__ import annotations

import numpy as np

from baselines.policy import Policy
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.envs.tasks.localization import belief_outcomes
from bounce_gym.markov.belief import BeliefFilter


class BeliefLocalizationPolicy(Policy):
    """Information gathering on a belief: at every bump, the angle of Φ whose next bump leaves
    the smallest expected entropy of the belief (`BeliefFilter.expected_entropy`; ties: the
    first angle).

    The policy keeps its own `BeliefFilter` on the sampled GCM and feeds it what the robot
    senses: the angle index it commanded itself and the clock in its observation (the first
    entry of a bounce-mode observation, ticks / ``max_clock``) at the next bump. ``act``
    ignores ``info`` (it may be None). The clock of the reset's drive is not used (the start
    pose is unknown): the belief starts uniform over the states the model has samples of.
    The claim itself is the task's (`bounce_gym.envs.tasks.localization`, filter "belief").
    """

    name = "belief (expected entropy)"

    def __init__(self, outcomes: BumpOutcomes, max_clock: int) -> None:
        self.filter = BeliefFilter(outcomes)
        self.max_clock = int(max_clock)
        self.last_action: int | None = None

    @classmethod
    def for_env(cls, env) -> BeliefLocalizationPolicy:
        """The policy on the env's sampled GCM (`belief_outcomes`), with as many samples as its localization task's
        belief filter uses (`LocalizationTask.model_samples`)."""
        base = env.unwrapped
        return cls(belief_outcomes(base.core, base.task.model_samples), base.options.max_clock)

    def reset(self, env) -> None:
        self.filter.reset()
        self.last_action = None

    def act(self, observation, info=None) -> int:
        if self.last_action is not None:
            ticks = int(round(float(observation[0]) * self.max_clock))
            self.filter.update(self.last_action, ticks)
        self.last_action = int(np.argmin(self.filter.expected_entropy()))
        return self.last_action
