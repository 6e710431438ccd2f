"""`BounceEnv`: one bouncing robot as a Gymnasium environment."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bounce_gym.envs.actions import action_space, to_angle
from bounce_gym.envs.base import EnvBase

SINGLE_ROBOT_TASKS = ("free", "navigation", "coverage", "localization")
#: arguments of `bounce_gym.envs.options.EnvOptions` that the single-robot env does not take
MULTI_ROBOT_ONLY = ("n_robots", "robot_collisions", "turn_angles", "min_sep_cells")


class BounceEnv(EnvBase, gym.Env):
    """A robot with only a contact sensor and a clock, bouncing around a polygon world.

    ## Description

    The robot drives straight until it bumps into a wall, rotates in place by a bounce angle and
    drives on (Alam, Bobadilla & Shell; Nilles, Ren, Becerra & LaValle). The agent chooses the
    bounce angle. Time runs in ticks: in one tick the robot drives ``step_length`` or, when it is
    blocked by a wall it faces, turns (a *bump tick*). Physics runs on an exact event-driven
    ``kinematic`` backend, on ``pymunk``, or on the discrete ``cell`` model of the planners.

    ## Action Space

    ``action_type="discrete"``: ``Discrete(len(angles))``, the index of the angle in Φ.
    ``action_type="continuous"``: ``Box(-1, 1, (1,), float32)``, mapped linearly onto
    ``angle_range``. With ``step_mode="bounce"`` every step starts with a bump, so every action is
    used; with ``step_mode="tick"`` the action is used only on bump ticks (observation
    ``contact == 1`` announces them). Out-of-space actions raise `ActionError` (never clipped).

    ## Observation Space

    A flat ``Box`` of float32: in tick mode ``contact`` (bump sensor pressed) — not in bounce
    mode, where every step ends in contact — then ``clock`` (ticks since the last bump /
    max_clock), then the optional sensing history, privileged pose and task features — see
    `bounce_gym.envs.core`. The true pose, cell, contact edge and task diagnostics are in ``info``.

    ## Rewards

    From the task: ``free`` — 0; ``navigation`` — by its ``reward`` option: ``progress``
    (default: +1 at the goal plus potential-based shaping by the geodesic distance to it),
    ``sparse`` or the papers' ``plan_cost`` (−w1 per tick, −(w2 − w1) per change of bounce
    angle, +goal_bonus at the goal), with the plan cost so far in ``info["plan_cost"]``;
    ``coverage`` — newly covered cells and the decrease of the L2 distance between visit
    histogram and target; ``localization`` — the drop in log2(candidate configurations) minus
    ``tick_cost`` per tick until localized, when a filter is plugged in, else 0. Each registered
    id's observation, reward and horizon: its page of the docs site ("About this id", from
    `bounce_gym.envs.registration.ABOUT`).

    ## Starting State

    Uniformly random pose in the free space (``robot_radius`` from the walls), unless the task
    or ``reset(options={"start": {"position": [x, y], "heading": rad}})`` fixes it. In bounce mode
    the robot then drives to its first contact, so the first action is the first bounce.

    ## Episode End

    Terminated when the task says so (navigation: goal reached; localization: localized, with a
    filter). Truncated by the registered ``max_episode_steps``, the one horizon of training and
    evaluation.

    ## Arguments

    ``render_mode`` (None, ``"human"`` or ``"rgb_array"``), then the keyword arguments declared
    in `bounce_gym.envs.options.EnvOptions` (type, default and meaning of each: the model, the
    signature of this class and the "Arguments" table of its docs page), the multi-robot ones
    excepted. Planners get the env's discrete model from `cell_model` (on ``env.unwrapped``).
    """

    #: the task names this env accepts
    tasks: tuple[str, ...] = SINGLE_ROBOT_TASKS
    not_taken = MULTI_ROBOT_ONLY

    def __init__(self, render_mode: str | None = None, **options: object) -> None:
        self._build(options, render_mode, self.tasks)
        self.action_space = action_space(self.options.action_type, len(self.options.angles[0]))
        self.observation_space = spaces.Box(self.core.obs_low, self.core.obs_high, dtype=np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        obs, info = self.core.reset(self.np_random, options)
        if self.render_mode == "human":
            self.render()
        return obs[0], _single(info)

    def step(self, action):
        if self.core.dynamics.state is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        angle = to_angle(action, self.options.action_type, self.options.angles[0],
                         self.options.angle_range[0])
        obs, reward, terminated, info = self.core.step_one(angle)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, False, info


def _single(info: dict) -> dict:
    """Per-robot arrays of the core's info, unpacked for the single robot (as
    `BounceCore.step_one` reports them)."""
    out = dict(info)
    out["position"] = info["position"][0]
    out["heading"] = float(info["heading"][0])
    out["cell"] = tuple(int(v) for v in info["cell"][0])
    for key in ("clock", "bumps", "contact_edge"):
        out[key] = int(info[key][0])
    del out["contact_robot"]
    return out
