"""A Gymnasium 1.x ``VectorEnv`` as a Stable-Baselines3 `VecEnv`.

Gymnasium's vector envs reset finished episodes on the *next* step (autoreset ``NEXT_STEP``);
SB3 expects the reset in the same step, with the last observation in
``info["terminal_observation"]`` and ``info["TimeLimit.truncated"]`` set when the time limit (not
the task) ended the episode. This view steps the vector env and, where episodes ended, resets
exactly those envs at once with ``reset(options={"reset_mask": done})`` (the option
SyncVectorEnv and `bounce_gym.envs.vector_env.BounceVectorEnv` take), so the vector env never
sees a next-step autoreset. ``seed(s)`` seeds the next reset of env i with s + i.

Attributes are read and set on the vector env itself (one object for every slot).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

__all__ = ["VectorToVecEnv"]


class VectorToVecEnv(VecEnv):
    """SB3 VecEnv view of a Gymnasium ``VectorEnv`` that takes ``options["reset_mask"]``."""

    def __init__(self, env: gym.vector.VectorEnv) -> None:
        self.env = env
        super().__init__(env.num_envs, env.single_observation_space, env.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        seeds = self._seeds
        seed = None if all(s is None for s in seeds) else list(seeds)
        options = self._options[0] if self._options and self._options[0] else None
        obs, _ = self.env.reset(seed=seed, options=options)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        obs, rewards, terminated, truncated, info = self.env.step(self._actions)
        done = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for key, value in info.items():
            if key.startswith("_"):
                continue
            mask = info[f"_{key}"]
            if mask.all():  # the usual case: one pass over the rows, no index arrays
                for one, item in zip(infos, value, strict=True):
                    one[key] = item
            else:
                for i in np.flatnonzero(mask):
                    infos[i][key] = value[i]
        if done.any():
            for i in np.flatnonzero(done):
                infos[i]["terminal_observation"] = obs[i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            fresh, _ = self.env.reset(options={"reset_mask": done})
            obs = np.where(done.reshape(-1, *([1] * (obs.ndim - 1))), fresh, obs)
        return obs, rewards.astype(np.float32), done, infos

    def close(self) -> None:
        self.env.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self.env, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices: VecEnvIndices = None,
                   **method_kwargs) -> list[Any]:
        result = getattr(self.env, method_name)(*method_args, **method_kwargs)
        return [result] * len(self._get_indices(indices))

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper],
                       indices: VecEnvIndices = None) -> list[bool]:
        return [False] * len(self._get_indices(indices))
