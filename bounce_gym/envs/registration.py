"""Registration of the environments with Gymnasium and PettingZoo (done on ``import bounce_gym``).

Gymnasium ids (``gym.make(id, **overrides)``):

| id | world | task | max_episode_steps |
|---|---|---|---|
| ``bounce_gym/Bounce-v0`` | two_rooms | free | 500 |
| ``bounce_gym/BounceNavigation-v0`` | lab_navigation | navigation (random start and goal) | 200 |
| ``bounce_gym/BounceCoverage-v0`` | lab_fig1 | coverage (uniform target) | 500 |
| ``bounce_gym/BounceLocalization-v0`` | lab_localization_a, φ = 45° | localization | 200 |
"""

from __future__ import annotations

import gymnasium as gym

GYM_ENVS = {
    "bounce_gym/Bounce-v0": ({"world": "two_rooms", "task": "free"}, 500),
    "bounce_gym/BounceNavigation-v0": (
        {"world": "lab_navigation", "task": "navigation", "history": 4}, 200),
    "bounce_gym/BounceCoverage-v0": ({"world": "lab_fig1", "task": "coverage"}, 500),
    "bounce_gym/BounceLocalization-v0": (
        {"world": "lab_localization_a", "task": "localization", "angles": (45.0,)}, 200),
}


def register_envs() -> None:
    """Register every environment id (idempotent)."""
    for env_id, (kwargs, steps) in GYM_ENVS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point="bounce_gym.envs.bounce_env:BounceEnv",
                         kwargs=kwargs, max_episode_steps=steps)
