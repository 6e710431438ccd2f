"""Several bouncing robots (Alam & Bobadilla): coverage by joint trajectories (Algorithm 1),
persistent monitoring on collision-free joint limit cycles (Algorithm 2), and the policies that
run both in `bounce_gym.envs.MultiBounceEnv`."""

from baselines.multirobot.coverage import CoverageResult, plan_coverage, random_start
from baselines.multirobot.monitoring import MonitoringResult, joint_monitoring_cycles
from baselines.multirobot.policies import CoveragePlanPolicy, MonitoringPlanPolicy

__all__ = ["CoveragePlanPolicy", "CoverageResult", "MonitoringPlanPolicy", "MonitoringResult",
           "joint_monitoring_cycles", "plan_coverage", "random_start"]
