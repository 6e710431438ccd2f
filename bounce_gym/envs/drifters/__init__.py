"""Profiling drifters in layered ocean currents (Alam 2018, thesis ch. 5) as environments:
`DrifterEnv` (Gymnasium, ``bounce_gym/Drifter-v0``) and `MultiDrifterEnv` (PettingZoo,
``bounce_gym/MultiDrifter-v0``)."""

from bounce_gym.envs.drifters.env import DrifterEnv
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv

__all__ = ["DrifterEnv", "MultiDrifterEnv"]
