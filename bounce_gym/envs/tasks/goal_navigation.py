"""Goal-conditioned navigation: dock at a wall pose of the cell model, from a start it joins.

The task of ``bounce_gym/BounceNavigation-v1`` (`bounce_gym.envs.goal_navigation_env`). Start and
goal are poses of the env's cell model (a cell centre with a bin heading); the goal is a
*decision pose* — a pose whose next move is blocked, where the robot bumps — and the robot
reaches it when a step ends there: the step's drive stops in the goal cell against the wall,
heading within ``heading_tolerance_deg`` (less than half a bin) of the goal's. A decision pose
is reached only by stopping in it (the drive cannot go on through a blocked pose), so this is
the papers' "the plan passes x_G" (Alam, Bobadilla & Shell 2017, Sec. IV) for goals a robot
that senses only contact and time can tell it is at: it knows where it is at a bump, not
between bumps.

What changes from v0's `NavigationTask` (Gymnasium's rule: a changed task gets a new version):

* **goals at the wall**, as above (v0: any pose, reached when a drive passes within
  ``goal_radius`` of it);
* **draws only pairs the model joins** (``draw="reachable"``, the default): the start is a pose
  from which the robot, after driving on to its first bump, can reach some other decision pose,
  and the goal a decision pose it can reach after one bounce or more, other than the one it
  first bumps in (`bounce_gym.cells.reach`, on the env's cell model); ``draw="any"`` draws
  any start pose and any decision pose as the goal, without asking the model (on the lab map
  about 3 in 4 such pairs are not joined). ``info["optimal_bounces"]`` is the
  fewest bounces the model needs for the pair (−1: never);
* **the sparse reward** ``goal_bonus`` (1) on arrival and 0 otherwise, the reward a goal-
  conditioned learner relabels (no shaping: a potential depends on the goal, which relabelling
  changes; no per-tick cost: it would depend on the step, not on the goals);
* `achieved` — the pose the robot is in after the step — is what the env reports as the
  achieved goal, and the arrival test compares it with the goal, so the reward recomputed from
  achieved and desired goals equals the step's reward.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from bounce_gym.cells.reach import UNREACHABLE, BounceReach
from bounce_gym.envs.tasks.base import StepEvents, pose_option
from bounce_gym.envs.tasks.navigation import NavigationTask
from bounce_gym.errors import ConfigError

#: the ``draw`` option of `GoalNavigationTask`
DRAWS = ("reachable", "any")
#: the goal radius the planners aim at (the goal cell's centre only), in step lengths
GOAL_RADIUS = 0.3
#: default heading tolerance at the goal, degrees
HEADING_TOLERANCE_DEG = 10.0


class GoalNavigationTask(NavigationTask):
    """Reach a goal pose of the cell model (module docstring).

    Args:
        start: a fixed pose ``{"position": [x, y], "heading": radians}`` (or per episode
            through ``reset(options=...)``), each snapped to the pose of the cell model that
            holds it (cell centre, nearest bin heading).
            None draws it (``draw``).
        goal: as ``start``; the goal must be a decision pose.
        draw: ``"reachable"`` (default) or ``"any"`` (module docstring).
        heading_tolerance_deg: in (0, half a bin) (default 10°).
        goal_bonus: the reward on arrival (default 1).
        w1: the plan-cost weight per tick of ``info["plan_cost"]``, as in `NavigationTask`.
        w2: the weight instead of w1 for a bump that changes the angle, as in `NavigationTask`.
    """

    option_keys = frozenset({"start", "goal"})

    def __init__(self, start: Mapping | None = None, goal: Mapping | None = None,
                 draw: str = "reachable", heading_tolerance_deg: float = HEADING_TOLERANCE_DEG,
                 goal_bonus: float = 1.0, w1: float = 1.0, w2: float = 100.0) -> None:
        super().__init__(start=start, goal=goal,
                         heading_tolerance_deg=heading_tolerance_deg, reward="sparse",
                         goal_bonus=goal_bonus, w1=w1, w2=w2, observe_task=False)
        if not isinstance(draw, str) or draw not in DRAWS:
            raise ConfigError(f"draw: expected one of {list(DRAWS)}, got {draw!r}")
        self.draw = draw

    def configure(self, core) -> None:
        # the goal region of the planners (`NavigationTask.goal_radius`): the goal cell's centre
        self.goal_radius_arg = GOAL_RADIUS * core.options.step_length
        super().configure(core)
        options = self.options
        #: the cell model whose poses are starts, goals and achieved goals
        self.model = model = core.cell_model()
        if self.heading_tolerance >= model.bin_width / 2:
            raise ConfigError(f"heading_tolerance_deg: expected less than half a bin "
                              f"({math.degrees(model.bin_width) / 2:g}°), got "
                              f"{math.degrees(self.heading_tolerance):g}")
        #: fewest bounces between the model's poses (`BounceReach`)
        self.reach = BounceReach(model, options.angles[0])
        #: (D, D) fewest bounces between decision poses (`BounceReach.bounces` at the goals)
        self.bounces = self.reach.bounces[:, self.reach.decisions]
        joins = ((self.bounces > 0) & ~np.eye(len(self.bounces), dtype=bool)).any(axis=1)
        #: the poses ``draw="reachable"`` draws starts from (uniformly)
        self.starts = np.flatnonzero(joins[self.reach.arrival])
        if self.draw == "reachable" and not len(self.starts):
            raise ConfigError("draw: 'reachable' needs a start pose that joins some goal pose, "
                              "and this world has none for these angles")
        arrivals = np.unique(self.reach.arrival[self.starts])
        plans = self.bounces[arrivals].astype(np.int64)
        plans[np.arange(len(arrivals)), arrivals] = UNREACHABLE  # a goal is not the first bump
        #: the fewest bounces of the hardest start/goal pair ``draw="reachable"`` draws: the
        #: longest optimal plan of the map (`UNREACHABLE` where no pair is joined)
        self.longest_plan = int(plans.max(initial=UNREACHABLE))
        #: per pose: its index among the decision poses (−1: not one)
        self.goal_index = np.full(model.n_cells, -1, dtype=np.int64)
        self.goal_index[self.reach.decisions] = np.arange(len(self.reach.decisions))
        #: the pose the robot is in after the last step (−1: outside the model's free cells,
        #: or heading farther than the tolerance from every bin)
        self.achieved = -1

    # -- poses -----------------------------------------------------------------------------
    def pose_of(self, position: np.ndarray, heading: float) -> int:
        """The cell model's pose holding ``position`` with the nearest bin to ``heading``
        (−1 outside the free cells)."""
        return int(self.model.cell_of(np.asarray(position, dtype=np.float64)[None],
                                      [heading])[0])

    def _snap(self, chosen) -> int:
        z = self.pose_of(chosen[0][0], float(chosen[1][0]))
        if z < 0:
            raise ConfigError(f"pose at {chosen[0][0].tolist()} is not in a free cell of the "
                              "cell model")
        return z

    def _pose(self, z: int) -> tuple[np.ndarray, np.ndarray]:
        centre, heading = self.model.configuration(np.array([z]))
        return centre.astype(np.float64), np.asarray(heading, dtype=np.float64)

    def start_poses(self, rng, options):
        given = {k: pose_option(options, k, 1) or pose_option(self._fixed, k, 1)
                 for k in ("start", "goal")}
        if given["start"] is not None:
            start = self._snap(given["start"])
        elif self.draw == "reachable":
            start = int(self.starts[rng.integers(len(self.starts))])
        else:
            start = int(rng.integers(self.model.n_cells))
        arrival = self.reach.arrival[start]
        bounces = self.bounces[arrival]
        decisions = self.reach.decisions
        if given["goal"] is not None:
            goal = self._snap(given["goal"])
            if self.goal_index[goal] < 0:
                raise ConfigError(f"goal: pose at {given['goal'][0][0].tolist()} is not a "
                                  "decision pose (the robot's next move there is not blocked)")
        elif self.draw == "reachable":
            # not the pose the first drive ends in: the robot would start at its goal
            choices = decisions[(bounces > 0) & (np.arange(len(decisions)) != arrival)]
            goal = int(choices[rng.integers(len(choices))])
        else:
            goal = int(decisions[rng.integers(len(decisions))])
        bounces = bounces[self.goal_index[goal]]
        #: pose numbers of the episode's start and goal, and the fewest bounces between them
        self.start_pose, self.goal_pose = start, goal
        self.optimal_bounces = int(bounces) if bounces > 0 else UNREACHABLE
        self.start, self.goal = self._pose(start), self._pose(goal)
        return self.start

    def reset(self, state, rng, options):
        self.achieved = self.pose_at(state.position[0], float(state.heading[0]))
        return super().reset(state, rng, options)

    def pose_at(self, position: np.ndarray, heading: float) -> int:
        """The cell model's pose of a robot at ``position`` with ``heading``: its cell and the
        bin its heading is within ``heading_tolerance`` of (−1 outside the free cells or between
        bins)."""
        z = self.pose_of(position, heading)
        error = (heading - float(self.model.configuration(max(z, 0))[1]) + math.pi) \
            % (2 * math.pi) - math.pi
        return z if z >= 0 and abs(error) <= self.heading_tolerance else -1

    # -- arrival ---------------------------------------------------------------------------
    def ticks_to_goal(self, events: StepEvents, goal: tuple | None = None) -> float | None:
        """Records the pose the step ends in (`achieved`); the step's ticks if it is the goal
        (``goal``: (position (1, 2), heading (1,)), default this episode's), else None."""
        self.achieved = self.pose_at(events.end[0], float(events.heading[0]))
        goal_pose = self.goal_pose if goal is None else self._snap(goal)
        return float(events.ticks) if self.achieved == goal_pose else None

    def _info(self, state) -> dict:
        info = super()._info(state)
        info["optimal_bounces"] = self.optimal_bounces
        return info

