"""Persistent monitoring by several robots: Alam & Bobadilla (Algorithm 2), the robots bouncing
with the planner's angles (`baselines.multirobot.policies.MonitoringPlanPolicy`).

Where every policy starts is the experiment's choice, ``planner_kwargs.start`` (one of
`baselines.multirobot.policies.MONITORING_STARTS`): ``draw`` (default) — every policy, the planner
included, starts from the env's random draw for the seed (the planner's row: ``planner``);
``cycle`` — every policy (planner, random, fixed, trained agents) starts where the planner
places the robots for the seed, on an accepted collision-free cycle
(`baselines.multirobot.policies.cycle_start`; the planner's row: ``planner (cycle start)``). So
no policy is credited for a start the others did not get.

Per episode, besides the team columns: ``in_region`` (``info["in_region_fraction"]`` averaged
over robots and steps) and ``encounters`` (robot pairs together at the end of a step, summed);
the planner also reports ``r`` (accepted periodic groups) and, with ``start: cycle``, ``period``
(of the group it runs) and ``predicted_in_region`` (the cell model's time in own region on that
group), beside the measured ``in_region`` on every backend.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym_experiments.families.multirobot import MultiRobot, TeamEpisode


class MonitoringEpisode(TeamEpisode):
    """Adds the time in own region and the encounters; ``start`` (seed → reset options, or
    ``None``) is the start the experiment imposes on every policy."""

    def __init__(self, env, start=None) -> None:
        super().__init__(env)
        self.start_of = start
        self.in_region = 0.0
        self.encounters = 0

    def start_options(self, seed):
        return None if self.start_of is None else self.start_of(seed)

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

    def validate(self, experiment):
        """Also ``planner_kwargs.start``: one of ``MONITORING_STARTS`` (default: the first)."""
        from baselines.multirobot.policies import MONITORING_STARTS

        super().validate(experiment)
        start = experiment["planner_kwargs"].setdefault("start", MONITORING_STARTS[0])
        if start not in MONITORING_STARTS:
            raise ConfigError(f"planner_kwargs.start: expected one of {list(MONITORING_STARTS)}, "
                              f"got {start!r}")

    def prepare(self, env, experiment):
        """The planner, built once per env: its policy row and, with ``start: cycle``, the start
        every policy gets (``None`` when neither is needed)."""
        if "planner" in experiment["policies"] or experiment["planner_kwargs"]["start"] == "cycle":
            return super().planner(env, experiment, None)
        return None

    def planner(self, env, experiment, setup):
        return setup

    def episode(self, env, policy, setup):
        cycle = setup is not None and setup.start == "cycle"
        return MonitoringEpisode(env, setup.cycle_options if cycle else None)


FAMILY = MultiRobotMonitoring()
