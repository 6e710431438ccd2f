"""Localization with a contact sensor and a clock: the angle-switching planner
(`baselines.localization.AngleSwitchPolicy`) against the filter's remaining candidates.

Per episode: ``success`` (localized) and ``candidates`` (left at the end).
"""

from __future__ import annotations

from experiments.families.base import SingleRobotFamily


class Localization(SingleRobotFamily):
    name = task = "localization"
    columns = (*SingleRobotFamily.columns, "success", "candidates")
    score = "success"

    def make_planner(self, env):
        from baselines.localization import AngleSwitchPolicy

        return AngleSwitchPolicy.for_env(env)

    def metrics(self, info):
        return {"success": bool(info.get("localized", False)),
                "candidates": int(info.get("candidates", -1))}


FAMILY = Localization()
