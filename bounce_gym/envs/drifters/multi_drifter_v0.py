"""PettingZoo-style module for the drifter fleet: ``parallel_env()``, ``env()``, ``raw_env``.

``parallel_env(**kwargs)`` is the native parallel form (`MultiDrifterEnv`); ``env(**kwargs)``
its AEC form through PettingZoo's ``parallel_to_aec`` conversion (drifters choose in turn; the
fleet moves once all have chosen), which also enforces the call order, with each action
checked as it is given (`bounce_gym.envs.aec_actions`); ``raw_env`` is the same
as ``env``.
"""

from bounce_gym.envs.aec_actions import checked_parallel_to_aec
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv


def parallel_env(**kwargs) -> MultiDrifterEnv:
    return MultiDrifterEnv(**kwargs)


def env(**kwargs):
    return checked_parallel_to_aec(MultiDrifterEnv(**kwargs))


raw_env = env
