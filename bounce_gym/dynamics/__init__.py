"""Robots moving in a world: bounce rules, noise models and motion backends.

`BounceDynamics` is the entry point; `rules` and `noise` hold the pure parts; backends
(`kinematic`, `pymunk`) only move robots and detect contacts. `Drifters` carries drifters
through a flow field (`bounce_gym.dynamics.advection`).
"""

from bounce_gym.dynamics import noise, rules
from bounce_gym.dynamics.advection import LAND_RULES, Drifters
from bounce_gym.dynamics.backends.base import MotionBackend
from bounce_gym.dynamics.noise import Exact, Interval, Reliable, make_noise
from bounce_gym.dynamics.simulator import BACKEND_NAMES, BounceDynamics, make_backend
from bounce_gym.dynamics.state import RobotState

__all__ = [
    "BACKEND_NAMES",
    "BounceDynamics",
    "Drifters",
    "Exact",
    "Interval",
    "LAND_RULES",
    "MotionBackend",
    "Reliable",
    "RobotState",
    "make_backend",
    "make_noise",
    "noise",
    "rules",
]
