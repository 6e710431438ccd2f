"""Navigation: reach the goal pose; the roadmap planner over (cell, bounce angle) and its
predicted cost (`baselines.navigation.NavigationPlanner`).

Per episode:

* ``success`` — the goal was reached; ``ticks_to_goal`` — when (successful episodes only);
* ``feasible`` — the planner's model says the episode can be solved at all: on the roadmap of
  the env's cell model (Alam, Bobadilla & Shell 2017, Sec. IV) some plan leads from the start
  cell to a goal cell. Random start/goal pairs are often not connected for a given Φ, and a
  policy cannot be blamed for those; ``success_feasible`` is ``success`` on the feasible
  episodes only (absent on the others), so its count is the number of feasible episodes;
* ``plan_cost`` — the papers' cost of the executed episode, w1 per tick plus w2 per change of
  bounce angle, as the env reports it (``info["plan_cost"]``, absent from envs that do not);
* for the planner, ``predicted_ticks`` and ``predicted_weight`` of its plan.

Feasibility needs the roadmap, so it is measured where the planner can run (discrete actions,
bounce steps); the first policy to meet a start/goal pair asks the roadmap, the others reuse the
answer.
"""

from __future__ import annotations

import numpy as np

from experiments.families.base import Episode, SingleRobotFamily


class Feasibility:
    """Whether the roadmap has a plan from the env's current start to its goal, remembered per
    (start, goal) pose pair."""

    def __init__(self) -> None:
        from baselines.navigation import NavigationPlanner

        self.probe = NavigationPlanner()
        self.known: dict[bytes, bool] = {}

    def __call__(self, env) -> bool:
        task = env.unwrapped.task
        key = np.concatenate([np.ravel(task.start[0]), np.ravel(task.start[1]),
                              np.ravel(task.goal[0]), np.ravel(task.goal[1])]).tobytes()
        if key not in self.known:
            self.probe.reset(env.unwrapped)
            self.known[key] = self.probe.plan is not None
        return self.known[key]


class NavigationEpisode(Episode):
    def __init__(self, env, feasibility: Feasibility | None) -> None:
        self.env = env
        self.feasibility = feasibility
        self.feasible: bool | None = None

    def start(self, info):
        if self.feasibility is not None:
            self.feasible = self.feasibility(self.env)
        return False

    def metrics(self, info):
        out = {"success": bool(info.get("is_success", False))}
        if self.feasible is not None:
            out["feasible"] = self.feasible
            if self.feasible:
                out["success_feasible"] = out["success"]
        if "ticks_to_goal" in info:
            out["ticks_to_goal"] = info["ticks_to_goal"]
        if info.get("plan_cost") is not None:
            out["plan_cost"] = float(info["plan_cost"])
        return out


class Navigation(SingleRobotFamily):
    name = task = "navigation"
    columns = (*SingleRobotFamily.columns, "success", "feasible", "success_feasible",
               "ticks_to_goal", "plan_cost", "predicted_ticks", "predicted_weight")
    score = "success"
    planner_attributes = ("predicted_ticks", "predicted_weight")

    def prepare(self, env, experiment):
        options = env.unwrapped.options
        if options.action_type != "discrete" or options.step_mode != "bounce":
            return None
        return Feasibility()

    def make_planner(self, env):
        from baselines.navigation import NavigationPlanner

        return NavigationPlanner()

    def episode(self, env, policy, setup):
        return NavigationEpisode(env, setup)


FAMILY = Navigation()
