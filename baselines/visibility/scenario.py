"""The visibility scenario of `evaluate.py`: reach a boundary segment from another one.

An experiment with a ``visibility`` block, e.g. ::

    - name: visibility-two-rooms
      env: bounce_gym/Bounce-v0
      env_kwargs: {world: two_rooms, bounce_rule: fixed, action_type: continuous,
                   angle_range: [0.5, 179.5]}
      visibility: {start: 0, goal: 16, plan: fewest}      # fewest | bottleneck | constant
      seeds: [0, 1, 2]
      max_steps: 10

starts every episode at a random point of P′ segment ``start``, heading into the wall, and counts
an episode as a success when a contact lands on segment ``goal`` (Nilles et al., Def. 14). The
``planner`` policy is `PlanPolicy` on the chosen safe plan; ``random`` draws the continuous action
uniformly; trained agents run as usual.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from baselines.visibility.graph import safe_graph
from baselines.visibility.partition import Partition, partition
from baselines.visibility.planning import (
    VisibilityPlan,
    bottleneck_plan,
    constant_strategy,
    fewest_bounce_plan,
)
from bounce_gym.errors import ConfigError

PLAN_KINDS = ("fewest", "bottleneck", "constant")


@dataclass
class VisibilityScenario:
    """The partition, safe graph and plan of one experiment."""

    part: Partition
    graph: object
    plan: VisibilityPlan
    start: int
    goal: int

    @classmethod
    def for_experiment(cls, env, spec: Mapping) -> VisibilityScenario:
        unknown = sorted(set(spec) - {"start", "goal", "plan", "max_arcs"})
        if unknown:
            raise ConfigError(f"visibility: unknown keys {unknown}; allowed are "
                              "['goal', 'max_arcs', 'plan', 'start']")
        opts = env.unwrapped.options
        if opts.bounce_rule != "fixed" or opts.action_type != "continuous":
            raise ConfigError("visibility: needs env_kwargs bounce_rule: fixed and "
                              "action_type: continuous")
        part = partition(opts.world)
        graph = safe_graph(part)
        start, goal = spec.get("start"), spec.get("goal")
        for key, value in (("start", start), ("goal", goal)):
            if not isinstance(value, int) or not 0 <= value < len(part.start):
                raise ConfigError(f"visibility.{key}: expected a segment id in "
                                  f"[0, {len(part.start)}), got {value!r}")
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

    def start_options(self, rng: np.random.Generator) -> dict:
        """A random point of the start segment, just off the wall, heading into it."""
        a, b = self.part.start[self.start], self.part.end[self.start]
        normal = self.part.normal[self.start]
        point = a + rng.uniform(0.01, 0.99) * (b - a) + 1e-3 * normal
        return {"start": {"position": point.tolist(),
                          "heading": math.atan2(-normal[1], -normal[0])}}

    def segment(self, info: dict) -> int:
        return int(self.part.locate([int(info["contact_edge"])], [info["position"]])[0])
