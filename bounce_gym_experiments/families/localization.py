"""Localization with a contact sensor and a clock: the angle-switching planner
(`baselines.localization.AngleSwitchPolicy`) against the filter's remaining candidates.

Per episode: ``success`` (localized), ``candidates`` (left at the end), ``correct`` (the claim is
the true decision state) and ``wrong_claim`` (it is not among the claim). With the task's
``filter_factory: belief`` the planner is `baselines.localization.BeliefLocalizationPolicy`,
with ``filter_factory: particles`` `baselines.localization.ParticleLocalizationPolicy`.
"""

from __future__ import annotations

from bounce_gym_experiments.families.base import SingleRobotFamily


class Localization(SingleRobotFamily):
    name = task = "localization"
    columns = (*SingleRobotFamily.columns, "success", "candidates", "correct", "wrong_claim")
    score = "success"

    def make_planner(self, env):
        from baselines.localization import (
            AngleSwitchPolicy,
            BeliefLocalizationPolicy,
            ParticleLocalizationPolicy,
        )
        from bounce_gym.envs.tasks.localization import BELIEF, PARTICLES

        if env.unwrapped.task.filter_factory == BELIEF:
            return BeliefLocalizationPolicy.for_env(env)
        if env.unwrapped.task.filter_factory == PARTICLES:
            return ParticleLocalizationPolicy.for_env(env)
        return AngleSwitchPolicy.for_env(env)

    def metrics(self, info):
        return {"success": bool(info.get("localized", False)),
                "candidates": int(info.get("candidates", -1)),
                "correct": bool(info.get("correct", False)),
                "wrong_claim": bool(info.get("wrong_claim", False))}


FAMILY = Localization()
