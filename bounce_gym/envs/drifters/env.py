"""`DrifterEnv`: one profiling drifter in layered ocean currents, as a Gymnasium environment."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bounce_gym.envs.drifters.base import DrifterEnvBase
from bounce_gym.envs.drifters.core import action_code

#: arguments of `bounce_gym.envs.drifters.options.DrifterOptions` only the multi-drifter env takes
MULTI_ONLY = ("n_drifters", "deploy")


class DrifterEnv(DrifterEnvBase, gym.Env):
    """A profiling drifter: carried by the current of its layer, it can only rise, sink or stay.

    ## Description

    The most minimal robot of Alam (2018, thesis ch. 5): a point mass in a stack of current
    layers (layer 0 = the surface) whose only control is U = {drift, up, down} (§5.3.2). Its
    horizontal motion is the flow's. The ``cell`` backend steps the thesis' discrete model
    (`bounce_gym.cells.DrifterCells`: the unit-step cell map with perfect-motion probability
    ρ, §5.4.2-5.4.3) exactly; the ``continuous`` backend integrates the flow with RK4
    (`bounce_gym.dynamics.Drifters`) for ``step_seconds`` per step.

    ## Action Space

    ``Discrete(3)``: 0 drift, 1 up (one layer shallower), 2 down (one layer deeper). Up or down
    is possible only where that layer exists and the drifter's cell is water in it;
    ``info["action_mask"]`` and `action_masks` (for sb3-contrib's MaskablePPO) give the legal
    actions. An illegal move drifts instead and sets ``info["illegal_action"]``
    (``illegal_action="error"`` raises `ActionError`). Actions outside the space raise
    `ActionError`.

    ## Observation Space

    A ``Box(0, 1)`` of float32: the layer (/ (L - 1)) and the clock (steps / ``clock_steps``),
    then optionally the last surface fix and whether it is fresh (``observe_fix``), the true
    position (``observe_pose``), and the goal's or region's mean position and layer (reach,
    stay). See `bounce_gym.envs.drifters.core`.

    ``info`` holds the true state: ``cell`` (layer, j, i), ``state`` (the cell model's state),
    ``position`` (x, y in the field's coordinates), ``layer``, ``steps``, ``action_mask`` (int8,
    3), ``illegal_action``; ``time`` (field seconds, continuous backend); reach:
    ``is_success``, ``distance_to_goal`` (metres); stay: ``in_region``, ``steps_in_region``;
    cover: ``coverage`` (fraction of the region visited), ``new_cells``.

    ## Rewards

    ``reach``: ``reward="success"`` 1 on the step that reaches the goal, else 0 (the mean
    return is the success probability); ``"thesis"``: 100 on reaching it, else -1 (Eq. 5.10).
    ``stay``: 1 per step ending in the region. ``cover``: newly visited region cells.

    ## Starting State

    A uniformly random surface water cell (the thesis deploys drifters at the surface) outside
    the goal, unless ``start`` or ``reset(options={"start": ...})`` gives a region
    (`bounce_gym.envs.drifters.regions`). ``reset(options=...)`` also takes ``goal`` (reach) or
    ``region`` (stay, cover) for one episode.

    ## Episode End

    Terminated when the drifter reaches the goal (reach; the goal is absorbing) or has visited
    the whole region (cover). Truncated by the registered ``max_episode_steps``.

    ## Arguments

    ``render_mode`` (None, ``"human"``, ``"rgb_array"``) and ``field_style`` (``"arrows"`` or
    ``"streamlines"``), then the keyword arguments declared in
    `bounce_gym.envs.drifters.options.DrifterOptions` but the fleet's ``n_drifters`` and
    ``deploy`` (type, default and meaning of each: the model, the signature of this class and
    the "Arguments" table of its docs page). Planners get the model from
    ``env.unwrapped.cell_model()``.
    """

    option_defaults = {"n_drifters": 1}
    not_taken = MULTI_ONLY

    def __init__(self, render_mode: str | None = None, field_style: str = "arrows",
                 **options: object) -> None:
        self._build(options, render_mode, field_style, clock_steps=None, start_key="start")
        self.action_space = spaces.Discrete(3)
        self.observation_space = spaces.Box(self.core.obs_low, self.core.obs_high,
                                            dtype=np.float32)
        self._started = False

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        obs, info = self.core.reset(self.np_random, options)
        self._started = True
        if self.render_mode == "human":
            self.render()
        return obs[0], _single(info)

    def step(self, action):
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        obs, rewards, terminated, info = self.core.step(np.array([action_code(action)]),
                                                        self.np_random)
        if self.render_mode == "human":
            self.render()
        return obs[0], float(rewards[0]), bool(terminated[0]), False, _single(info)

    def action_masks(self) -> np.ndarray:
        """(3,) bool, the legal actions now (the hook sb3-contrib's MaskablePPO calls)."""
        return self.core.legal()[0]

    def _render_layer(self) -> int:
        return int(self.core.fleet.layers()[0])


def _single(info: dict) -> dict:
    """The core's per-drifter rows, unpacked for the one drifter."""
    out = dict(info)
    out["cell"] = tuple(int(v) for v in info["cell"][0])
    out["state"] = int(info["state"][0])
    out["position"] = info["position"][0].copy()
    out["layer"] = int(info["layer"][0])
    out["action_mask"] = info["action_mask"][0]
    out["illegal_action"] = bool(info["illegal_action"][0])
    for key in ("is_success", "in_region"):
        if key in out:
            out[key] = bool(out[key][0])
    for key, kind in (("distance_to_goal", float), ("steps_in_region", int)):
        if key in out:
            out[key] = kind(out[key][0])
    return out
