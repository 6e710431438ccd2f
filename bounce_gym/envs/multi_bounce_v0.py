"""PettingZoo-style module for the multi-robot environment: ``env()``, ``parallel_env()``.

``parallel_env(**kwargs)`` is the native parallel form (`MultiBounceEnv`); ``env(**kwargs)`` the
event-driven AEC form (`MultiBounceAEC`) wrapped in PettingZoo's order-enforcing wrapper (the env
itself refuses a bad action with `ActionError`, naming the agent and what is allowed; PettingZoo's
assert-out-of-bounds wrapper would answer a bare ``AssertionError`` first); ``raw_env`` is the
unwrapped AEC class.
"""

from pettingzoo.utils import wrappers

from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv

raw_env = MultiBounceAEC


def env(**kwargs) -> wrappers.OrderEnforcingWrapper:
    return wrappers.OrderEnforcingWrapper(MultiBounceAEC(**kwargs))


def parallel_env(**kwargs) -> MultiBounceEnv:
    return MultiBounceEnv(**kwargs)
