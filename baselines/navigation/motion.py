"""The bump-to-bump motion the continuous-angle planners simulate, and the continuous action.

`simulated_motion` wraps the env's own simulator (`bounce_gym.dynamics.bump_sampler`) behind
the two calls the planners make — ``bumps`` (robots at bump poses bump with given angles and
drive to their next bump) and ``reset_drives`` (robots placed in the free space drive to their
first contact, as a bounce-mode reset does) — so that a faster bump-to-bump map with the same
two calls can stand in for it.

A continuous action is one float32 number a in [−1, 1] that the env maps linearly onto its
angle range (`bounce_gym.envs.actions.to_angle`). A planner that simulates an angle must
simulate the angle its action will execute, so `continuous_action` rounds angles to actions and
`executed_angle` maps actions back exactly as the env does.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.model import CellModel
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.dynamics.bump_sampler import reset_drives, simulate_bumps


class _SimulatedMotion:
    """The env's simulator behind ``bumps`` and ``reset_drives`` (module docstring)."""

    def __init__(self, model: CellModel, dynamics: dict) -> None:
        self.model, self.dynamics = model, dict(dynamics)

    def bumps(self, angles: np.ndarray, action: np.ndarray, point: np.ndarray,
              heading: np.ndarray, rng: np.random.Generator, max_ticks: int) -> BumpOutcomes:
        return simulate_bumps(self.model, angles, action, point, heading, rng, self.dynamics,
                              max_ticks)

    def reset_drives(self, point: np.ndarray, heading: np.ndarray, rng: np.random.Generator,
                     max_ticks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return reset_drives(self.model, self.dynamics, point, heading, rng, max_ticks)


def simulated_motion(model: CellModel, dynamics: dict) -> _SimulatedMotion:
    """The bump-to-bump motion of ``dynamics`` (`BounceDynamics` arguments with ``world``),
    decision states numbered by ``model``."""
    return _SimulatedMotion(model, dynamics)


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
