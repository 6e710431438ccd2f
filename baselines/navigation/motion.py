"""The continuous action, as the continuous-angle planners simulate it.

(The planners move robots from bump to bump through `bounce_gym.dynamics.bump_table.
bump_motion`: the tabulated map on pymunk's dynamic physics, the simulator elsewhere.)

A continuous action is one float32 number a in [−1, 1] that the env maps linearly onto its
angle range (`bounce_gym.envs.actions.to_angle`). A planner that simulates an angle must
simulate the angle its action will execute, so `continuous_action` rounds angles to actions and
`executed_angle` maps actions back exactly as the env does.
"""

from __future__ import annotations

import numpy as np


def continuous_action(angle: np.ndarray, angle_range: tuple[float, float]) -> np.ndarray:
    """The float32 actions in [−1, 1] nearest to bounce angles (radians) in ``angle_range``."""
    lo, hi = angle_range
    a = 2.0 * (np.asarray(angle, dtype=np.float64) - lo) / (hi - lo) - 1.0
    return np.clip(a, -1.0, 1.0).astype(np.float32)


def executed_angle(action: np.ndarray, angle_range: tuple[float, float]) -> np.ndarray:
    """The bounce angles (radians) the env executes for float32 ``action`` (its own formula,
    `bounce_gym.envs.actions.to_angle`, to the last bit)."""
    lo, hi = angle_range
    return lo + (np.asarray(action, dtype=np.float32).astype(np.float64) + 1.0) / 2.0 * (hi - lo)


def exact_angles(angle: np.ndarray, angle_range: tuple[float, float]) -> np.ndarray:
    """Bounce angles rounded to what their actions execute."""
    return executed_angle(continuous_action(angle, angle_range), angle_range)
