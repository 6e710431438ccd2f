"""Nilles et al. (IJRR 2021): the boundary partition P', the bounce visibility graph and safe
actions (`partition`, `graph`), and the dynamics of bounce sequences — transition maps,
contraction, limit cycles (`dynamics`)."""

from baselines.visibility.graph import SafeGraphReachability, bvg, reachability, safe_graph
from baselines.visibility.partition import Partition, partition
from baselines.visibility.planning import (
    PatrolPlan,
    PatrolPolicy,
    PlanPolicy,
    VisibilityPlan,
    bottleneck_plan,
    constant_strategy,
    fewest_bounce_plan,
    monte_carlo,
    patrol,
)
from baselines.visibility.scenario import VisibilityScenario

__all__ = [
    "Partition",
    "PatrolPlan",
    "PatrolPolicy",
    "PlanPolicy",
    "SafeGraphReachability",
    "VisibilityPlan",
    "VisibilityScenario",
    "bottleneck_plan",
    "bvg",
    "constant_strategy",
    "fewest_bounce_plan",
    "monte_carlo",
    "partition",
    "patrol",
    "reachability",
    "safe_graph",
]
