"""A PettingZoo parallel env as a Stable-Baselines3 `VecEnv`, for parameter sharing.

**Parameter sharing.** Every robot is one sub-environment of the VecEnv: slot i of every batch
(observation, action, reward, done, info) belongs to agent ``possible_agents[i]``. SB3 then trains
*one* policy on the experience of all robots — the robots share the network's parameters and each
acts on its own observation (decentralised execution with a centralised, shared learner). This is
what SuperSuit's ``pettingzoo_env_to_vec_env_v1`` does; this adapter
replaces it without the dependency. It needs every agent to have the same observation and action
space. With ``MultiBounceEnv`` robots observe only their own contact/clock (plus task features), so
a shared policy cannot tell robots apart unless the observation says who is who.

**Episodes and autoreset.** SB3's same-step autoreset: when the parallel env's episode ends (no
live agents left), every slot reports ``done=True`` with ``info["terminal_observation"]`` (the
agent's last observation) and ``info["TimeLimit.truncated"]`` (truncated and not terminated), the
env is reset at once, and the returned observations are the first ones of the new episode.
An agent that leaves early while others go on reports ``done=True`` (with its terminal
observation) once; until the whole episode ends its slot then returns zero observations and zero
reward with ``done=False`` and its actions are ignored ("black death", as SuperSuit's
``black_death_v3``), and when the episode ends it reports ``done=True`` again with a zero
terminal observation.

**Seeding.** ``seed(s)`` (SB3's `VecEnv.seed`) seeds the next reset of the one underlying env with
``s``; ``set_options`` passes reset options from slot 0.

**Attributes and methods.** All slots share one env, so ``get_attr`` returns the env's attribute
once per requested slot, ``set_attr`` sets it once, and ``env_method`` calls the method **once**
and returns its result once per requested slot.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

__all__ = ["ParallelToVecEnv", "evaluate_shared_policy"]


class ParallelToVecEnv(VecEnv):
    """SB3 VecEnv over a PettingZoo ``ParallelEnv``: one slot per agent (module docstring).

    Args:
        env: the parallel env; all ``possible_agents`` must share one observation space and one
            action space (equal spaces).
    """

    def __init__(self, env: Any) -> None:
        self.env = env
        self.agents = list(env.possible_agents)
        if not self.agents:
            raise ValueError("the parallel env has no possible agents")
        obs_space = env.observation_space(self.agents[0])
        act_space = env.action_space(self.agents[0])
        for a in self.agents[1:]:
            if env.observation_space(a) != obs_space or env.action_space(a) != act_space:
                raise ValueError(f"parameter sharing needs equal spaces for all agents; {a!r} "
                                 "differs from the first agent")
        if not isinstance(obs_space, spaces.Box):
            raise ValueError(f"only Box observations are supported, got {obs_space}")
        super().__init__(len(self.agents), obs_space, act_space)
        self._actions: np.ndarray | None = None
        self._dead = np.zeros(self.num_envs, dtype=bool)

    # -- the VecEnv contract ----------------------------------------------------------------
    def reset(self) -> np.ndarray:
        seed = self._seeds[0]
        options = self._options[0] or None
        obs, infos = self.env.reset(seed=seed, options=options)
        self._reset_seeds()
        self._reset_options()
        self._dead[:] = False
        self.reset_infos = [dict(infos.get(a, {})) for a in self.agents]
        return self._stack(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        if self._actions is None:
            raise RuntimeError("step_wait() without step_async()")
        live = list(self.env.agents)
        actions = {a: self._action(self._actions[i]) for i, a in enumerate(self.agents)
                   if a in live}
        self._actions = None
        obs, rewards, terms, truncs, infos = self.env.step(actions)
        n = self.num_envs
        obs_arr = self._stack(obs)
        rew = np.zeros(n, dtype=np.float32)
        dones = np.zeros(n, dtype=bool)
        out_infos: list[dict] = [{} for _ in range(n)]
        episode_over = not self.env.agents
        for i, a in enumerate(self.agents):
            if a in live:
                rew[i] = float(rewards.get(a, 0.0))
                out_infos[i] = dict(infos.get(a, {}))
                term, trunc = bool(terms.get(a, False)), bool(truncs.get(a, False))
                if term or trunc:
                    dones[i] = True
                    out_infos[i]["terminal_observation"] = obs_arr[i].copy()
                    out_infos[i]["TimeLimit.truncated"] = trunc and not term
                    self._dead[i] = True
                    obs_arr[i] = 0.0
            elif episode_over:  # dead since an earlier step: close its dummy episode
                dones[i] = True
                out_infos[i]["terminal_observation"] = np.zeros_like(obs_arr[i])
                out_infos[i]["TimeLimit.truncated"] = True
        if episode_over:
            obs_arr = self.reset()
        return obs_arr, rew, dones, out_infos

    def close(self) -> None:
        self.env.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.env, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices: VecEnvIndices = None,
                   **method_kwargs) -> list[Any]:
        result = getattr(self.env, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper],
                       indices: VecEnvIndices = None) -> list[bool]:
        wrapped, env = False, self.env
        while env is not None:
            if isinstance(env, wrapper_class):
                wrapped = True
                break
            env = getattr(env, "env", None)
        return [wrapped for _ in self._get_indices(indices)]

    def get_images(self) -> list[np.ndarray | None]:
        frame = self.env.render() if self.render_mode == "rgb_array" else None
        return [frame for _ in range(self.num_envs)]

    # -- internals ---------------------------------------------------------------------------
    def _stack(self, obs: dict) -> np.ndarray:
        shape, dtype = self.observation_space.shape, self.observation_space.dtype
        out = np.zeros((self.num_envs, *shape), dtype=dtype)
        for i, a in enumerate(self.agents):
            if a in obs and not self._dead[i]:
                out[i] = obs[a]
        return out

    def _action(self, action: np.ndarray) -> Any:
        if isinstance(self.action_space, spaces.Discrete):
            return int(np.asarray(action).reshape(-1)[0])
        return np.asarray(action, dtype=self.action_space.dtype).reshape(self.action_space.shape)


def evaluate_shared_policy(model: Any, env: Any, seed: int | None = None,
                           deterministic: bool = True) -> dict[str, float]:
    """Run one episode of a parallel env with one shared SB3 policy (``model.predict`` on the
    stacked observations of the live agents). Returns each agent's return."""
    obs, _ = env.reset(seed=seed)
    returns = dict.fromkeys(env.possible_agents, 0.0)
    while env.agents:
        live = list(env.agents)
        batch = np.stack([obs[a] for a in live])
        actions, _ = model.predict(batch, deterministic=deterministic)
        step_actions = {}
        for a, act in zip(live, actions, strict=True):
            space = env.action_space(a)
            step_actions[a] = int(act) if isinstance(space, spaces.Discrete) else np.asarray(act)
        obs, rewards, _, _, _ = env.step(step_actions)
        for a, r in rewards.items():
            returns[a] += float(r)
    return returns
