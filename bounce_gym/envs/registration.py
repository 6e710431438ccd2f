"""Registration of the environments with Gymnasium and PettingZoo (done on ``import bounce_gym``).

Gymnasium ids (``gym.make(id, **overrides)``):

| id | world | task | max_episode_steps |
|---|---|---|---|
| ``bounce_gym/Bounce-v0`` | two_rooms | free | 500 |
| ``bounce_gym/BounceNavigation-v0`` | lab_navigation | navigation (random start and goal) | 200 |
| ``bounce_gym/BounceCoverage-v0`` | lab_fig1 | coverage (uniform target) | 500 |
| ``bounce_gym/BounceLocalization-v0`` | lab_localization_a, φ = 45°, cell backend | localization with the combinatorial filter | 200 |

The free, navigation and coverage ids also have a ``vector_entry_point``: ``gym.make_vec(id,
num_envs=N)`` builds a `bounce_gym.envs.vector_env.BounceVectorEnv` (N robots stepped as one batch).

PettingZoo ids (``pettingzoo.make("parallel" | "aec", id, **overrides)``), ``max_cycles`` 500:
``bounce_gym/MultiBounce-v0`` (grid_15x15, 4 robots, free), ``bounce_gym/MultiBounceCoverage-v0``
(grid_15x15, 4 robots, shared coverage) and ``bounce_gym/MultiBounceMonitoring-v0`` (grid_20x12,
4 robots, one region each).

Drifters (thesis ch. 5, `bounce_gym.envs.drifters`): the Gymnasium id ``bounce_gym/Drifter-v0``
(one profiling drifter, scb_like flow, cell backend, reach task; max_episode_steps 200) and the
PettingZoo id ``bounce_gym/MultiDrifter-v0`` (4 drifters covering the surface; max_cycles 500).
"""

from __future__ import annotations

import gymnasium as gym
import pettingzoo

GYM_ENVS = {
    "bounce_gym/Bounce-v0": ({"world": "two_rooms", "task": "free"}, 500),
    "bounce_gym/BounceNavigation-v0": (
        {"world": "lab_navigation", "task": "navigation", "history": 4}, 200),
    "bounce_gym/BounceCoverage-v0": ({"world": "lab_fig1", "task": "coverage"}, 500),
    "bounce_gym/BounceLocalization-v0": (
        {"world": "lab_localization_a", "task": "localization", "angles": (45.0,),
         "backend": "cell",
         "task_kwargs": {"filter_factory": "combinatorial"}}, 200),
}

#: the ids whose envs `BounceVectorEnv` batches (localization's filter is not batched)
VECTOR_ENTRY_POINT = "bounce_gym.envs.vector_env:BounceVectorEnv"
VECTOR_IDS = ("bounce_gym/Bounce-v0", "bounce_gym/BounceNavigation-v0",
              "bounce_gym/BounceCoverage-v0")

PETTINGZOO_ENVS = {
    "bounce_gym/MultiBounce-v0": {"world": "grid_15x15", "task": "free"},
    "bounce_gym/MultiBounceCoverage-v0": {"world": "grid_15x15", "task": "coverage"},
    "bounce_gym/MultiBounceMonitoring-v0": {"world": "grid_20x12", "task": "monitoring"},
}


#: drifter ids (thesis ch. 5): Gymnasium id -> (entry point, max_episode_steps)
DRIFTER_GYM_ENVS = {
    "bounce_gym/Drifter-v0": ("bounce_gym.envs.drifters.env:DrifterEnv", 200),
}
#: drifter PettingZoo ids -> the module with ``parallel_env`` and ``env``
DRIFTER_PETTINGZOO_ENVS = {
    "bounce_gym/MultiDrifter-v0": "bounce_gym.envs.drifters.multi_drifter_v0",
}


def is_pettingzoo_id(env_id: str) -> bool:
    """Whether ``env_id`` is one of the multi-robot PettingZoo ids (not a Gymnasium id)."""
    return env_id in PETTINGZOO_ENVS or env_id in DRIFTER_PETTINGZOO_ENVS


_ENTRY = {
    "parallel": "bounce_gym.envs.multi_bounce_v0:parallel_env",
    "aec": "bounce_gym.envs.multi_bounce_v0:env",
}


def register_envs() -> None:
    """Register every environment id (idempotent)."""
    for env_id, (kwargs, steps) in GYM_ENVS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point="bounce_gym.envs.bounce_env:BounceEnv",
                         vector_entry_point=VECTOR_ENTRY_POINT if env_id in VECTOR_IDS else None,
                         kwargs=kwargs, max_episode_steps=steps)
    for env_id, (entry_point, steps) in DRIFTER_GYM_ENVS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point=entry_point, max_episode_steps=steps)
    for env_type, registry in (("parallel", pettingzoo.parallel_registry),
                               ("aec", pettingzoo.aec_registry)):
        for env_id, kwargs in PETTINGZOO_ENVS.items():
            if env_id not in registry:
                pettingzoo.register(env_type, env_id, entry_point=_ENTRY[env_type],
                                    max_cycles=500, kwargs=kwargs)
        for env_id, module in DRIFTER_PETTINGZOO_ENVS.items():
            if env_id not in registry:
                function = "parallel_env" if env_type == "parallel" else "env"
                pettingzoo.register(env_type, env_id, entry_point=f"{module}:{function}",
                                    max_cycles=500)
