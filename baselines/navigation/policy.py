"""Navigation plans executed in BounceEnv."""

from __future__ import annotations

import math

import numpy as np

from baselines.navigation.roadmap import Plan, Roadmap, goal_cells
from baselines.policy import POSE_OBSERVED, Policy
from bounce_gym.errors import ConfigError

# -- policies ---------------------------------------------------------------------------------

def _env_angles_deg(env) -> np.ndarray:
    options = env.options
    if options.step_mode != "bounce":
        raise ConfigError("plans execute with step_mode='bounce' (one step per bump)")
    if options.action_type != "discrete":
        raise ConfigError("plans execute with discrete actions (indices into Φ)")
    return np.degrees(np.asarray(options.angles[0], dtype=np.float64))


def _angle_index(env_deg: np.ndarray, angle: float) -> int:
    diff = np.abs((env_deg - angle + 180.0) % 360.0 - 180.0)
    hits = np.flatnonzero(diff < 1e-6)
    if not len(hits):
        raise ConfigError(f"plan angle {angle:g}° is not one of the env's angles "
                          f"{[round(float(a), 6) for a in env_deg]}")
    return int(hits[0])


class PlanExecutor(Policy):
    """Replay a plan in a `BounceEnv` (``step_mode="bounce"``, discrete actions).

    Every env step starts with a bump; the executor answers with the plan's next bump angle (as
    an index into the env's Φ). Before each bump it compares the env's clock (ticks since the
    last bump, ``info["clock"]``) with the plan's run of 0s before that bump; a mismatch sets
    ``deviated`` (and is recorded in ``deviations`` as (bump number, expected, observed)). The
    first bump after `reset` is preceded by the drive of the env's reset, which is the plan's
    leading run of 0s. Once the plan's bumps are used up the executor repeats the last angle
    (no change penalty) and sets ``exhausted``.

    Args:
        plan: the plan to replay; None (no plan) acts ``fallback_action`` throughout.
        fallback_action: action when there is no plan or no angle was used yet.
        check_first_clock: compare the clock before the first bump (False when a plan starts in
            the middle of an episode, after an unplanned drive).
    """

    name = "plan"

    def __init__(self, plan: Plan | None, fallback_action: int = 0,
                 check_first_clock: bool = True) -> None:
        self.plan = plan
        self.fallback_action = int(fallback_action)
        self.check_first_clock = bool(check_first_clock)
        self._schedule: list[tuple[int, int]] = []
        self.reset_state()

    def reset_state(self) -> None:
        self.next_bump = 0
        self.deviated = False
        self.exhausted = False
        self.deviations: list[tuple[int, int, int]] = []
        self.last_action: int | None = None

    def bind(self, env) -> None:
        """Map the plan's angles to the env's action indices (without resetting the counters)."""
        env_deg = _env_angles_deg(env)
        self._schedule = [] if self.plan is None else [
            (_angle_index(env_deg, angle), zeros) for angle, zeros in self.plan.segments()]

    def reset(self, env) -> None:
        self.bind(env)
        self.reset_state()

    def expected_clock(self) -> int | None:
        """The plan's run of 0s before the next bump (None once the plan is used up)."""
        if self.next_bump >= len(self._schedule):
            return None
        return self._schedule[self.next_bump][1]

    def checks_clock(self) -> bool:
        """Whether the clock is compared before the next bump."""
        return self.next_bump > 0 or self.check_first_clock

    def act(self, observation, info):
        if self.next_bump >= len(self._schedule):
            self.exhausted = self.plan is not None
            return self.fallback_action if self.last_action is None else self.last_action
        action, zeros = self._schedule[self.next_bump]
        clock = info.get("clock") if isinstance(info, dict) else None
        if clock is not None and self.checks_clock() and int(clock) != zeros:
            self.deviated = True
            self.deviations.append((self.next_bump, zeros, int(clock)))
        self.next_bump += 1
        self.last_action = action
        return action


class NavigationPlanner(Policy):
    """The reference navigation policy: plan on the roadmap at reset, then execute the plan.

    At ``reset(env)`` it reads the episode's start and goal poses from the env's navigation task
    (``env.task.start`` / ``env.task.goal``), maps the start to its cell and the goal to the
    cells of the task's goal region (centres within ``goal_radius`` of the goal point, bins
    within ``heading_tolerance``; see `goal_cells`), and plans on the layered roadmap with the
    task's weights w1, w2 (so the plan minimises the env's cost). The cell model is the env's
    (``env.cell_model()``): the cell backend's own, or on the other backends the model at cell
    size = step length with the env's ``cell_bins``, where the plan is replayed open-loop.

    The plan is `Roadmap.bounce_plan`: the env tests arrival only in the steps after its reset
    drive, so a minimum plan that meets the goal before its first bump (on the drive, or
    start = goal) is replaced by the drive and a plan of at least one tick back into the goal
    region (None if there is none). The robot follows the plan by counting ticks, as the papers'
    robot does. Where the plan runs out before the episode ends, it replans (a plan of at least
    one tick) from the cell it must be in, which it tracks by stepping
    the deterministic cell model with its own actions (dead reckoning on the model, no privileged
    state). With ``replan_from_info=True`` it replans from the true pose in ``info`` instead,
    which also recovers from deviations under noise.

    Attributes:
        plan: the current plan (None: the goal is unreachable in the model; acts angle 0).
        executor: the `PlanExecutor` following it.
        replans: how many times it replanned in this episode.
    """

    name = "roadmap planner"

    @property
    def predicted_ticks(self) -> int | None:
        """Ticks of the episode's plan (start to goal), or None without a plan."""
        return None if self.plan is None else int(self.plan.ticks)

    @property
    def predicted_weight(self) -> float | None:
        """Roadmap weight of the episode's plan (w1 per tick, w2 per angle change)."""
        return None if self.plan is None else float(self.plan.weight)

    def __init__(self, w1: float | None = None, w2: float | None = None,
                 replan_from_info: bool = False) -> None:
        self.w1, self.w2 = w1, w2
        self.replan_from_info = bool(replan_from_info)
        if self.replan_from_info:
            self.information = POSE_OBSERVED
        self._cache_key = None
        self.roadmap: Roadmap | None = None
        self.plan: Plan | None = None
        self.executor = PlanExecutor(None)
        self.replans = 0

    # -- model --------------------------------------------------------------------------------
    def _roadmap(self, env) -> Roadmap:
        task, model = env.task, env.cell_model()
        w1 = task.w1 if self.w1 is None else self.w1
        w2 = task.w2 if self.w2 is None else self.w2
        angles = tuple(np.round(_env_angles_deg(env), 9).tolist())
        key = (id(model), angles, w1, w2)  # the roadmap keeps the model alive: ids stay unique
        if key != self._cache_key:
            self.roadmap = Roadmap(model, angles, w1, w2)
            self._cache_key = key
        return self.roadmap

    def reset(self, env) -> None:
        env = getattr(env, "unwrapped", env)  # gym.make wrappers hide the task
        task = env.task
        if getattr(task, "name", None) != "navigation":
            raise ConfigError("NavigationPlanner needs an env with task='navigation'")
        rm = self._roadmap(env)
        model = rm.model
        self._env_deg = _env_angles_deg(env)
        start_pos, start_head = task.start[0][0], float(task.start[1][0])
        goal_pos, goal_head = task.goal[0][0], float(task.goal[1][0])
        self.start_cell = int(model.cell_of(start_pos[None], [start_head])[0])
        self.goal_cells = goal_cells(model, goal_pos, goal_head, task.goal_radius,
                                     task.heading_tolerance)
        self.replans = 0
        self.plan = None
        if self.start_cell >= 0 and len(self.goal_cells):
            # the env sees the goal only after the reset drive: `Roadmap.bounce_plan`
            self.plan = rm.bounce_plan(self.start_cell, self.goal_cells)
        self.executor = PlanExecutor(self.plan)
        self.executor.reset(env)
        self._env = env
        # the robot's cell after the env's reset drive, predicted on the model
        self.cell = self._drive(self.start_cell) if self.start_cell >= 0 else -1

    # -- dead reckoning on the model ----------------------------------------------------------
    def _drive(self, z: int) -> int:
        model = self.roadmap.model
        for _ in range(model.n_cells + 1):
            p, k = model.decode(z)
            t = int(model.targets[k, p])
            if t < 0:
                return z
            z = int(model.cell_id(t, k))
        raise AssertionError("a straight drive never reached a wall")

    def _after_bump(self, z: int, action: int) -> int:
        model = self.roadmap.model
        p, k = model.decode(z)
        turn = model.angle_bins(math.radians(float(self._env_deg[action])))
        return self._drive(int(model.cell_id(p, (k + turn) % model.n_bins)))

    def act(self, observation, info):
        ex = self.executor
        info = info if isinstance(info, dict) else {}
        if self.plan is not None:
            expected = ex.expected_clock()
            clock = info.get("clock")
            off_plan = (self.replan_from_info and expected is not None and clock is not None
                        and ex.checks_clock() and int(clock) != expected)
            if expected is None or off_plan:
                self._replan(info)
                ex = self.executor
        action = ex.act(observation, info)
        if self.cell >= 0:
            self.cell = self._after_bump(self.cell, int(action))
        return action

    def _replan(self, info: dict) -> None:
        """A new plan from the current cell (model-tracked, or the true pose of ``info``)."""
        here = self.cell
        if self.replan_from_info and "position" in info and "heading" in info:
            here = int(self.roadmap.model.cell_of(np.asarray(info["position"])[None],
                                                  [float(info["heading"])])[0])
            self.cell = here
        # at least one tick: ``here`` is where a step starts, and the env tests arrival only
        # in the step (an empty plan from a goal cell would never arrive)
        new = self.roadmap.plan(here, self.goal_cells, nonempty=True) if here >= 0 else None
        if new is None or new.ticks == 0:
            return  # nothing better to do: the executor repeats its last angle
        self.replans += 1
        self.plan = new
        last = self.executor.last_action
        self.executor = PlanExecutor(new, check_first_clock=False)
        self.executor.bind(self._env)
        self.executor.last_action = last

    @property
    def deviated(self) -> bool:
        return self.executor.deviated
