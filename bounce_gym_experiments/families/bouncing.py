"""One robot bouncing with no task (``task="free"``): no planner, no metrics beyond return,
steps and ticks."""

from __future__ import annotations

from bounce_gym_experiments.families.base import SingleRobotFamily


class Bouncing(SingleRobotFamily):
    name = "bouncing"


FAMILY = Bouncing()
