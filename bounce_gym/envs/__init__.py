"""Gymnasium and PettingZoo environments: the env classes behind the registered ids
(`bounce_gym.envs.registration`). ``import bounce_gym`` registers the ids without importing
any env; the classes named here load on first use (``from bounce_gym.envs import BounceEnv``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # what type checkers and the API reference read; at run time: __getattr__
    from bounce_gym.envs.bounce_env import BounceEnv
    from bounce_gym.envs.drifters.env import DrifterEnv
    from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv
    from bounce_gym.envs.goal_navigation_env import GoalNavigationEnv
    from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv
    from bounce_gym.envs.patrol.env import PatrolEnv
    from bounce_gym.envs.vector_env import BounceVectorEnv

#: each env class and the module (under bounce_gym.envs) that defines it
_HOMES = {
    "BounceEnv": "bounce_env",
    "BounceVectorEnv": "vector_env",
    "DrifterEnv": "drifters.env",
    "GoalNavigationEnv": "goal_navigation_env",
    "MultiBounceAEC": "multi_bounce_env",
    "MultiBounceEnv": "multi_bounce_env",
    "MultiDrifterEnv": "drifters.multi_env",
    "PatrolEnv": "patrol.env",
}

__all__ = ["BounceEnv", "BounceVectorEnv", "DrifterEnv", "GoalNavigationEnv", "MultiBounceAEC",
           "MultiBounceEnv", "MultiDrifterEnv", "PatrolEnv"]


def __getattr__(name: str):
    """An env class of `__all__`, imported from its module on first use (PEP 562)."""
    if name in _HOMES:
        return getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
