"""PettingZoo-style module for the patrol environment: ``parallel_env()``, ``env()``,
``raw_env``.

``parallel_env(**kwargs)`` is the native parallel form (`PatrolEnv`); ``env(**kwargs)`` its AEC
form through PettingZoo's ``parallel_to_aec`` conversion (the agents choose in turn; the world
moves once all have chosen), which also enforces the call order, with each action checked as
it is given (`bounce_gym.envs.aec_actions`); ``raw_env`` is the same as ``env``.
"""

from bounce_gym.envs.aec_actions import checked_parallel_to_aec
from bounce_gym.envs.patrol.env import PatrolEnv


def parallel_env(**kwargs) -> PatrolEnv:
    return PatrolEnv(**kwargs)


def env(**kwargs):
    return checked_parallel_to_aec(PatrolEnv(**kwargs))


raw_env = env
