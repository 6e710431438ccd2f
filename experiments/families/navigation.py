"""Navigation: reach the goal pose; the roadmap planner over (cell, bounce angle) and its
predicted cost (`baselines.navigation.NavigationPlanner`).

Per episode: ``success``, ``ticks_to_goal`` (successful episodes only) and, for the planner,
``predicted_ticks`` and ``predicted_weight``.
"""

from __future__ import annotations

from experiments.families.base import SingleRobotFamily


class Navigation(SingleRobotFamily):
    name = task = "navigation"
    columns = (*SingleRobotFamily.columns, "success", "ticks_to_goal", "predicted_ticks",
               "predicted_weight")
    planner_attributes = ("predicted_ticks", "predicted_weight")

    def make_planner(self, env):
        from baselines.navigation import NavigationPlanner

        return NavigationPlanner()

    def metrics(self, info):
        out = {"success": bool(info.get("is_success", False))}
        if "ticks_to_goal" in info:
            out["ticks_to_goal"] = info["ticks_to_goal"]
        return out


FAMILY = Navigation()
