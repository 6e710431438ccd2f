"""Persistent monitoring by several robots: Alam & Bobadilla (Algorithm 2), the robots started
on an accepted collision-free periodic group (`baselines.multirobot.policies.MonitoringPlanPolicy`).

Per episode, besides the team columns: ``in_region`` (``info["in_region_fraction"]`` averaged
over robots and steps) and ``encounters`` (robot pairs together at the end of a step, summed);
the planner also reports ``r`` (accepted periodic groups), ``period`` (of the group it runs) and
``predicted_in_region`` (the cell model's time in own region on that group), beside the measured
``in_region`` on every backend.
"""

from __future__ import annotations

import numpy as np

from bounce_gym_experiments.families.multirobot import MultiRobot, TeamEpisode


class MonitoringEpisode(TeamEpisode):
    def __init__(self, env) -> None:
        super().__init__(env)
        self.in_region = 0.0
        self.encounters = 0

    def step(self, info):
        super().step(info)
        self.in_region += float(np.mean(info["in_region_fraction"]))
        self.encounters += int(info["encounters"])
        return False

    def metrics(self, info):
        return {**super().metrics(info), "in_region": self.in_region / max(self.steps, 1),
                "encounters": self.encounters}


class MultiRobotMonitoring(MultiRobot):
    name = "multirobot monitoring"
    task = "monitoring"
    table = "multi-robot monitoring"
    columns = ("experiment", "policy", "robots", "episodes", "seeds", "in_region",
               "predicted_in_region", "encounters", "robot_contacts", "r", "period", "ticks")
    labels = frozenset({"robots", "r"})
    score = "in_region"
    planner_attributes = ("r", "period", "predicted_in_region")
    planner_class = "MonitoringPlanPolicy"

    def episode(self, env, policy, setup):
        return MonitoringEpisode(env)


FAMILY = MultiRobotMonitoring()
