"""Navigation: reach a goal pose."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from bounce_gym.envs.tasks.base import StepEvents, Task, _normalised, pose_option, tick_length
from bounce_gym.errors import ConfigError
from bounce_gym.validate import flag, number


class NavigationTask(Task):
    """Reach a goal pose: within ``goal_radius`` of the goal point, heading within tolerance.

    Args:
        start, goal: ``{"position": [x, y], "heading": radians}``; None draws one per episode
            (uniformly in the free space, or — on the cell backend — a random cell centre and
            bin heading).
            Both can also be given per episode through ``reset(options={"start": ..., "goal": ...})``.
        goal_radius: size of the goal region (default: one step length).
        heading_tolerance_deg: heading tolerance at the goal (default 22.5°, half a 45° bin).
        w1: cost per tick; w2: cost of a bump that changes the bounce angle (charged instead of
            w1). The first angle is free. Defaults are the paper's w1 = 1, w2 = 100.
        goal_bonus: reward on arrival.
        observe_task: append the start and goal poses (normalised) to the observation — the
            planners of the papers know both, so a fair RL agent needs them too.

    The goal counts as reached when the robot's straight path of a step passes through the goal
    region while its heading is within tolerance; only the ticks up to that point are charged.
    """

    name = "navigation"
    option_keys = frozenset({"start", "goal"})

    def __init__(self, start: Mapping | None = None, goal: Mapping | None = None,
                 goal_radius: float | None = None, heading_tolerance_deg: float = 22.5,
                 w1: float = 1.0, w2: float = 100.0, goal_bonus: float = 100.0,
                 observe_task: bool = True) -> None:
        self._fixed = {"start": start, "goal": goal}
        for key in ("start", "goal"):
            if self._fixed[key] is not None:
                pose_option(self._fixed, key, 1)
        heading_tolerance_deg = number("heading_tolerance_deg", heading_tolerance_deg,
                                       minimum=0.0, strict=True)
        if heading_tolerance_deg > 180:
            raise ConfigError(f"heading_tolerance_deg: expected (0, 180], got {heading_tolerance_deg}")
        if goal_radius is not None:
            goal_radius = number("goal_radius", goal_radius, minimum=0.0, strict=True)
        w1, w2 = number("w1", w1), number("w2", w2)
        if not (w1 >= 0 and w2 >= w1):
            raise ConfigError(f"w1, w2: expected 0 <= w1 <= w2, got w1={w1}, w2={w2}")
        self.goal_radius_arg = goal_radius
        self.heading_tolerance = math.radians(heading_tolerance_deg)
        self.w1, self.w2 = w1, w2
        self.goal_bonus = number("goal_bonus", goal_bonus)
        self.observe_task = flag("observe_task", observe_task)

    def configure(self, core) -> None:
        super().configure(core)
        options = self.options
        if options.n_robots != 1:
            raise ConfigError("task 'navigation' is a single-robot task (n_robots must be 1)")
        self.goal_radius = float(self.goal_radius_arg or options.step_length)
        # on the cell backend, random starts and goals are cells (centre and bin heading): the
        # papers' x_I and x_G
        self._cells = core.cell_model() if options.backend == "cell" else None
        for key, pose in self._fixed.items():
            if pose is not None:
                position = pose_option(self._fixed, key, 1)[0]
                if not options.world.contains(position, options.robot_radius).all():
                    raise ConfigError(f"task_kwargs.{key}: position {position[0].tolist()} is "
                                      "not in the free space")

    @property
    def observation_size(self) -> int:
        return 8 if self.observe_task else 0

    def start_poses(self, rng, options):
        chosen = {k: pose_option(options, k, 1) or pose_option(self._fixed, k, 1)
                  for k in ("start", "goal")}
        world, radius = self.options.world, self.options.robot_radius
        for key in ("start", "goal"):
            if chosen[key] is None and self._cells is not None:
                p, k = rng.integers(self._cells.n_positions), rng.integers(self._cells.n_bins)
                chosen[key] = (self._cells.centres[[p]], np.array([k * self._cells.bin_width]))
            elif chosen[key] is None:
                chosen[key] = (world.sample_free(rng, 1, radius), rng.uniform(0, 2 * np.pi, 1))
            elif not world.contains(chosen[key][0], radius).all():
                raise ConfigError(f"{key} position {chosen[key][0][0].tolist()} is not in the "
                                  "free space")
        self.start, self.goal = chosen["start"], chosen["goal"]
        return self.start

    def reset(self, state, rng, options):
        self.last_angle = math.nan
        self.reached = False
        return self._info(state)

    def _info(self, state) -> dict:
        gap = float(np.hypot(*(state.position[0] - self.goal[0][0])))
        return {"goal_position": self.goal[0][0].copy(), "goal_heading": float(self.goal[1][0]),
                "distance_to_goal": gap, "is_success": self.reached}

    def _ticks_to_goal(self, events: StepEvents) -> float | None:
        """Ticks into the step at which the robot first enters the goal region, else None."""
        err = (events.heading[0] - self.goal[1][0] + np.pi) % (2 * np.pi) - np.pi
        if abs(err) > self.heading_tolerance:
            return None
        p0, p1, g = events.start[0], events.end[0], self.goal[0][0]
        seg = p1 - p0
        length = float(np.hypot(*seg))
        rel = p0 - g
        if rel @ rel <= self.goal_radius**2:
            s = 0.0
        elif length == 0:
            return None
        else:
            d = seg / length
            b = float(rel @ d)
            disc = b * b - (float(rel @ rel) - self.goal_radius**2)
            if disc < 0:
                return None
            s = -b - math.sqrt(disc)  # where the segment's line enters the goal disk
            if s < 0 or s > length:
                return None  # the disk lies behind the start, or beyond the end
        per_tick = float(tick_length(self.options, events.heading[:1])[0])
        drive = math.ceil(s / per_tick - 1e-9)
        return float(events.bumps[0] + drive)

    def step(self, state, events):
        changed = bool(events.angle_changed[0])
        arrive = self._ticks_to_goal(events)
        ticks = events.ticks if arrive is None else min(events.ticks, arrive)
        reward = -self.w1 * ticks - (self.w2 - self.w1) * changed
        info = self._info(state)
        if arrive is not None:
            self.reached = True
            reward += self.goal_bonus
            info.update(is_success=True, ticks_to_goal=int(state.ticks - events.ticks + arrive))
        info["angle_changed"] = changed
        return np.array([reward]), np.array([self.reached]), info

    def observation(self, state):
        if not self.observe_task:
            return np.zeros((1, 0), dtype=np.float32)
        feats = [_normalised(self.options.world, self.start[0][0]),
                 [math.cos(self.start[1][0]), math.sin(self.start[1][0])],
                 _normalised(self.options.world, self.goal[0][0]),
                 [math.cos(self.goal[1][0]), math.sin(self.goal[1][0])]]
        return np.concatenate(feats).astype(np.float32)[None, :]

    def render_layers(self):
        return {"goal": (*self.goal[0][0], self.goal_radius, float(self.goal[1][0]),
                         self.heading_tolerance)}


