"""Navigation with a bouncing robot (Alam, Bobadilla & Shell): the roadmap over the cell model,
minimum-cost plans, and the policies that execute them in `bounce_gym.envs.BounceEnv`."""

from baselines.navigation.policy import NavigationPlanner, PlanExecutor
from baselines.navigation.roadmap import BUMP, FORWARD, AllPlans, Plan, Roadmap, goal_cells

__all__ = ["BUMP", "FORWARD", "AllPlans", "NavigationPlanner", "Plan", "PlanExecutor", "Roadmap",
           "goal_cells"]
