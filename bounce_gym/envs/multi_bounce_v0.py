"""PettingZoo-style module for the multi-robot environment: ``env()``, ``parallel_env()``.

``parallel_env(**kwargs)`` is the native parallel form (`MultiBounceEnv`); ``env(**kwargs)`` the
event-driven AEC form (`MultiBounceAEC`) wrapped in PettingZoo's order-enforcing and
assert-out-of-bounds wrappers; ``raw_env`` is the unwrapped AEC class.
"""

from pettingzoo.utils import wrappers

from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv

raw_env = MultiBounceAEC


def env(**kwargs) -> wrappers.OrderEnforcingWrapper:
    return wrappers.OrderEnforcingWrapper(wrappers.AssertOutOfBoundsWrapper(MultiBounceAEC(**kwargs)))


def parallel_env(**kwargs) -> MultiBounceEnv:
    return MultiBounceEnv(**kwargs)
