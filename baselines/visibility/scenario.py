"""The visibility scenarios of `evaluate.py`: reach a boundary segment, or patrol a cycle.

An experiment with a ``visibility`` block, e.g. ::

    - name: visibility-two-rooms
      env: bounce_gym/Bounce-v0
      env_kwargs: {world: two_rooms, bounce_rule: fixed, action_type: continuous,
                   angle_range: [0.5, 179.5]}
      visibility: {start: 0, goal: 16, plan: fewest}      # fewest | bottleneck | constant
      seeds: [0, 1, 2]
      max_steps: 10

starts every episode at a random point of P′ segment ``start``, heading into the wall, and counts
an episode as a success when a contact lands on segment ``goal`` (Nilles et al., Def. 14). With
``{start: 0, patrol: [0, 1, 2, 3, 4, 5, 6], theta: 0.1}`` instead of ``goal`` the task is Def. 15:
the planner is the contracting cycle of G_safe visiting those original edges in order (one fixed
action ``theta`` if given), and an episode succeeds when its last contact lies within 1e-3 ×
diameter of the cycle's fixed point (the robot converged to the limit cycle). The ``planner``
policy is `PlanPolicy` / `PatrolPolicy`; ``random`` draws the continuous action uniformly;
trained agents run as usual.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from baselines.policy import Policy
from baselines.visibility.graph import safe_graph
from baselines.visibility.partition import Partition, partition
from baselines.visibility.planning import (
    PatrolPlan,
    PatrolPolicy,
    PlanPolicy,
    VisibilityPlan,
    bottleneck_plan,
    constant_strategy,
    fewest_bounce_plan,
    patrol,
)
from bounce_gym.errors import ConfigError
from bounce_gym.validate import unknown_keys

PLAN_KINDS = ("fewest", "bottleneck", "constant")


@dataclass
class VisibilityScenario:
    """The partition, safe graph and plan of one experiment (goal or patrol)."""

    part: Partition
    graph: object
    plan: VisibilityPlan | PatrolPlan
    start: int
    goal: int | None  # None for a patrol

    @classmethod
    def for_experiment(cls, env, spec: Mapping) -> VisibilityScenario:
        allowed = {"start", "goal", "plan", "max_arcs", "patrol", "theta", "max_len"}
        unknown_keys("visibility", spec, allowed)
        opts = env.unwrapped.options
        if opts.bounce_rule != "fixed" or opts.action_type != "continuous":
            raise ConfigError("visibility: needs env_kwargs bounce_rule: fixed and "
                              "action_type: continuous")
        part = partition(opts.world)
        graph = safe_graph(part)
        start = spec.get("start")
        _check_segment("visibility.start", start, part)
        if ("goal" in spec) == ("patrol" in spec):
            raise ConfigError("visibility: give exactly one of 'goal' (a segment) and 'patrol' "
                              "(a sequence of original edge ids)")
        if "patrol" in spec:
            return cls(part, graph, cls._patrol(graph, part, spec, start), start, None)
        goal = spec["goal"]
        _check_segment("visibility.goal", goal, part)
        kind = spec.get("plan", "fewest")
        if kind not in PLAN_KINDS:
            raise ConfigError(f"visibility.plan: expected one of {PLAN_KINDS}, got {kind!r}")
        max_arcs = int(spec.get("max_arcs", 4))
        plan = {"fewest": lambda: fewest_bounce_plan(graph, start, goal),
                "bottleneck": lambda: bottleneck_plan(graph, start, goal, max_arcs),
                "constant": lambda: constant_strategy(graph, start, goal, max_arcs)}[kind]()
        if plan is None:
            raise ConfigError(f"visibility: no safe {kind} plan from segment {start} to {goal}")
        return cls(part, graph, plan, start, goal)

    @staticmethod
    def _patrol(graph, part: Partition, spec: Mapping, start: int) -> PatrolPlan:
        edges = spec["patrol"]
        if not isinstance(edges, list) or not all(isinstance(e, int) for e in edges):
            raise ConfigError(f"visibility.patrol: expected a list of edge ids, got {edges!r}")
        theta = spec.get("theta")
        plan = patrol(graph, part, edges, max_len=int(spec.get("max_len", len(edges) + 2)),
                      start=start, theta=None if theta is None else float(theta))
        if plan is None or not plan.stable:
            raise ConfigError(f"visibility.patrol: no stable cycle visiting edges {edges}")
        return plan

    def planner(self, seed: int = 0) -> Policy:
        if self.goal is None:
            return PatrolPolicy(self.plan, self.part, self.graph, seed=seed,
                                name=f"patrol cycle (C(F) = {self.plan.coefficient:.2g})")
        return PlanPolicy(self.plan, self.part, seed=seed, name=f"safe plan ({self.plan.kind})")

    def start_options(self, rng: np.random.Generator) -> dict:
        """A random point of the start segment, just off the wall, heading into it."""
        a, b = self.part.start[self.start], self.part.end[self.start]
        normal = self.part.normal[self.start]
        point = a + rng.uniform(0.01, 0.99) * (b - a) + 1e-3 * normal
        return {"start": {"position": point.tolist(),
                          "heading": math.atan2(-normal[1], -normal[0])}}

    def segment(self, info: dict) -> int:
        return int(self.part.locate([int(info["contact_edge"])], [info["position"]])[0])

    def done(self, info: dict) -> bool:
        """A goal scenario ends when a contact lands on the goal segment."""
        return self.goal is not None and self.segment(info) == self.goal

    def success(self, info: dict) -> bool:
        """Goal reached, or (patrol) the last contact is on the limit cycle."""
        if self.goal is not None:
            return self.done(info)
        seg = self.segment(info)
        if seg not in self.plan.cycle:
            return False
        target = self.plan.fixed_point.points[self.plan.cycle.index(seg)]
        gap = float(np.hypot(*(np.asarray(info["position"]) - target)))
        return gap <= 1e-3 * self.part_diameter

    @property
    def part_diameter(self) -> float:
        pts = np.vstack((self.part.start, self.part.end))
        return float(np.hypot(*(pts.max(axis=0) - pts.min(axis=0))))


def _check_segment(field: str, value: object, part: Partition) -> None:
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < len(part.start):
        raise ConfigError(f"{field}: expected a segment id in [0, {len(part.start)}), "
                          f"got {value!r}")
