"""`MapHorizon`: the time limit of an env whose horizon depends on its map.

Gymnasium sets an id's time limit (``TimeLimit``) from the ``max_episode_steps`` it registers,
before the env — and so its map — exists. An env whose horizon follows from its map
(``BounceNavigation-v1``: `bounce_gym.envs.goal_navigation_env.HORIZON_FACTOR` times the longest
optimal plan of the map) registers none and this wrapper instead (``additional_wrappers``, which
``gym.make`` applies after its own ``TimeLimit``): it truncates at the env's ``horizon``, and
reports it as ``env.spec.max_episode_steps``. Where ``gym.make`` was given a
``max_episode_steps``, its ``TimeLimit`` is already inside and the wrapper leaves the limit to
it, so an explicit horizon wins, shorter or longer.
"""

from __future__ import annotations

from copy import deepcopy

import gymnasium as gym
from gymnasium.wrappers import TimeLimit


def _has_time_limit(env: gym.Env) -> bool:
    while isinstance(env, gym.Wrapper):
        if isinstance(env, TimeLimit):
            return True
        env = env.env
    return False


class MapHorizon(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Truncate after ``env.unwrapped.horizon`` steps, unless a ``TimeLimit`` is inside.

    Attributes:
        max_episode_steps: the limit this wrapper applies (None: the inner ``TimeLimit``'s).
        _elapsed_steps: steps since the last reset (named as ``TimeLimit`` names its counter).
    """

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        self.max_episode_steps: int | None = (
            None if _has_time_limit(env) else int(env.unwrapped.horizon))  # type: ignore[attr-defined]
        self._elapsed_steps = 0

    def reset(self, **kwargs):
        self._elapsed_steps = 0
        return self.env.reset(**kwargs)

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        self._elapsed_steps += 1
        if self.max_episode_steps is not None and self._elapsed_steps >= self.max_episode_steps:
            truncated = True
        return observation, reward, terminated, truncated, info

    @property
    def spec(self):
        """The inner spec with this wrapper, and with the horizon as ``max_episode_steps``."""
        spec = super().spec
        if spec is not None and self.max_episode_steps is not None \
                and spec.max_episode_steps != self.max_episode_steps:
            spec = deepcopy(spec)
            spec.max_episode_steps = self.max_episode_steps
            self._cached_spec = spec
        return spec
