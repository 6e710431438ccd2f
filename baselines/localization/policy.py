"""The angle-switching planner as a policy."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from baselines.localization.planner import AngleSwitchPlanner
from baselines.policy import Policy
from bounce_gym.cells import CellModel
from bounce_gym.markov.automata import ObservationError
from bounce_gym.markov.filters import ActiveLocalizationFilter


class AngleSwitchPolicy(Policy):
    """Reference policy for the localization task: at every bump, the planner's angle.

    It runs its own `ActiveLocalizationFilter` on what the robot senses — rebuilt from the
    task's ``info`` (``observations``, ``clock``, ``step_ticks``), nothing privileged — and asks
    `AngleSwitchPlanner` for the angle minimising the worst-case candidate count.
    ``act(observation, info)`` returns the discrete action (the index of the angle).
    """

    name = "planner (angle switching)"

    def __init__(self, model: CellModel, angles: Sequence[float], depth: int = 1,
                 open_world: bool = True) -> None:
        self.planner = AngleSwitchPlanner(model, angles, depth=depth)
        self.filter = ActiveLocalizationFilter(model, angles, open_world=open_world)
        self.angles = self.planner.angles

    @classmethod
    def for_env(cls, env, depth: int = 1) -> AngleSwitchPolicy:
        """The policy for a `BounceEnv`: its angles, on its cell model (``env.cell_model()``)."""
        base = env.unwrapped
        return cls(base.cell_model(), base.options.angles[0], depth=depth)

    def act(self, observation, info: dict) -> int:
        self.observe(info)
        if self.filter.trapped or self.filter.size == 0:
            return 0  # the observations left the model: no better choice than the first angle
        try:
            angle = self.planner.choose(self.filter.candidates)
        except ObservationError:
            return 0  # not at a bump (tick mode, driving): the action is not used
        return int(np.argmin(np.abs(np.asarray(self.angles) - angle)))

    def observe(self, info: dict) -> None:
        """Feed the filter the ticks the env reported since the previous call."""
        if info["observation_count"] == 0:  # a new episode: the drive to the first contact
            self.filter.reset()
            for _ in range(int(info["clock"])):
                self.filter.update(0)
        else:
            bumps, _, angle = info["observation"]
            for _ in range(bumps):
                self.filter.update(1, angle)
            for _ in range(int(info["step_ticks"]) - bumps):
                self.filter.update(0)
