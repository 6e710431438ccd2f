"""`BounceEnv`: one bouncing robot as a Gymnasium environment."""

from __future__ import annotations

from collections.abc import Mapping

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bounce_gym.envs.actions import action_space, to_angle
from bounce_gym.envs.core import BounceCore
from bounce_gym.envs.options import parse_options
from bounce_gym.envs.tasks import make_task
from bounce_gym.errors import ConfigError

SINGLE_ROBOT_TASKS = ("free", "navigation", "coverage", "localization")


class BounceEnv(gym.Env):
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

    A flat ``Box`` of float32: ``contact`` (bump sensor pressed), ``clock`` (ticks since the last
    bump / max_clock), then the optional sensing history, privileged pose and task features — see
    `bounce_gym.envs.core`. The true pose, cell, contact edge and task diagnostics are in ``info``.

    ## Rewards

    From the task: ``free`` — 0; ``navigation`` — −w1 per tick, −(w2 − w1) per change of bounce
    angle, +goal_bonus at the goal; ``coverage`` — newly covered cells and the decrease of the L2
    distance between visit histogram and target; ``localization`` — the drop in log2(candidate
    configurations) when a filter is plugged in, else 0.

    ## Starting State

    Uniformly random pose in the free space (``robot_radius`` from the walls), unless the task
    or ``reset(options={"start": {"position": [x, y], "heading": rad}})`` fixes it. In bounce mode
    the robot then drives to its first contact, so the first action is the first bounce.

    ## Episode End

    Terminated when the task says so (navigation: goal reached; localization: localized, with a
    filter). Truncated by the registered ``max_episode_steps``.

    ## Arguments

    * ``world``: zoo name (`bounce_gym.worlds.names()`), map-file path, or `World`.
    * ``task``: ``"free"``, ``"navigation"``, ``"coverage"``, ``"localization"`` or a `Task`;
      ``task_kwargs``: keyword arguments of the task class (see `bounce_gym.envs.tasks`).
    * ``backend``: ``"kinematic"`` (exact, continuous), ``"pymunk"`` (physics engine) or
      ``"cell"`` (the papers' discrete cell-to-cell model: cell size = ``step_length``,
      ``cell_bins`` orientation bins, ``corner_rule``; relative rule and discrete actions whose
      angles are whole bins; one tick = one cell step or one rotation).
    * ``bounce_rule``: ``"relative"`` (Alam), ``"fixed"``, ``"specular"``, ``"monotonic"``,
      ``"nilles_relative"`` (Nilles).
    * ``angles``: the set Φ, in degrees (default 45, 90, 135).
    * ``angle_range``: (low, high) degrees for continuous actions (default: min/max of Φ).
    * ``noise``: None, ``{"type": "reliable", "r": 0.8, "eps_deg": 5}`` or
      ``{"type": "interval", "lo_deg": -5, "hi_deg": 5}``.
    * ``robot_radius`` (default 0, a point), ``step_length`` (default 1: one cell per tick).
    * ``step_mode``: ``"bounce"`` (one step = the bump, then driving to the next contact) or
      ``"tick"`` (one step = one tick).
    * ``action_type``: ``"discrete"`` or ``"continuous"``.
    * ``history``: number of (segment ticks, angle) pairs in the observation (default 0).
    * ``privileged``: add the true pose to the observation (default False).
    * ``cell_bins``, ``corner_rule``: the cell backend's orientation bins (default 8) and diagonal
      rule (default ``"target_only"``, see `bounce_gym.cells.model`).
    * ``render_mode``: None, ``"human"`` or ``"rgb_array"``.

    ## Version History

    * v0: initial release.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 10}

    def __init__(
        self,
        world: object = "two_rooms",
        task: object = "free",
        task_kwargs: Mapping | None = None,
        backend: str = "kinematic",
        bounce_rule: str = "relative",
        angles: object = (45.0, 90.0, 135.0),
        angle_range: object = None,
        noise: object = None,
        robot_radius: float = 0.0,
        step_length: float = 1.0,
        step_mode: str = "bounce",
        action_type: str = "discrete",
        history: int = 0,
        privileged: bool = False,
        cell_bins: int = 8,
        corner_rule: str = "target_only",
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ConfigError(f"render_mode: expected None or one of "
                              f"{self.metadata['render_modes']}, got {render_mode!r}")
        self.options = parse_options(
            world=world, n_robots=1, backend=backend, bounce_rule=bounce_rule, angles=angles,
            angle_range=angle_range, noise=noise, robot_radius=robot_radius,
            step_length=step_length, step_mode=step_mode, action_type=action_type,
            history=history, privileged=privileged, robot_collisions="ignore",
            cell_bins=cell_bins, corner_rule=corner_rule,
        )
        self.core = BounceCore(self.options, make_task(task, task_kwargs, SINGLE_ROBOT_TASKS))
        self.render_mode = render_mode
        self.action_space = action_space(self.options.action_type, len(self.options.angles[0]))
        self.observation_space = spaces.Box(self.core.obs_low, self.core.obs_high, dtype=np.float32)
        self._renderer = None

    @property
    def world(self):
        return self.options.world

    @property
    def task(self):
        return self.core.task

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
        obs, rewards, terminated, info = self.core.step(np.array([angle]))
        if self.render_mode == "human":
            self.render()
        return obs[0], float(rewards[0]), bool(terminated[0]), False, _single(info)

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode to the env")
            return None
        from bounce_gym.envs.render.view import draw_core

        if self._renderer is None:
            from bounce_gym.envs.render.renderer import Renderer

            self._renderer = Renderer(self.world)
        frame = draw_core(self._renderer, self.core)
        if self.render_mode == "human":
            self._renderer.show(frame, self.metadata["render_fps"])
            return None
        return frame

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_renderer"] = None  # pygame objects are rebuilt on the next render()
        return state


def _single(info: dict) -> dict:
    """Per-robot arrays of the core's info, unpacked for the single robot."""
    out = dict(info)
    out["position"] = info["position"][0]
    out["heading"] = float(info["heading"][0])
    out["cell"] = tuple(int(v) for v in info["cell"][0])
    for key in ("clock", "bumps", "contact_edge"):
        out[key] = int(info[key][0])
    del out["contact_robot"]
    return out
