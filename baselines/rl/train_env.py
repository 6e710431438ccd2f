"""The VecEnv an agent trains on: the envs, the monitor, and the observation/reward wrappers.

From the bottom up:

1. the envs (``vec_env``): the native batch (`bounce_gym.envs.vector_env.BounceVectorEnv` seen
   through `baselines.rl.vector_vec_env.VectorToVecEnv`), or SB3's ``DummyVecEnv``
   (``sync``) / ``SubprocVecEnv`` (``subproc``) of ``gym.make`` copies, each inside
   `SnapshotEnv`; for a PettingZoo id the parameter-sharing adapter
   (`baselines.rl.parallel_vec_env.ParallelToVecEnv`, one slot per robot). Env i is seeded with
   seed + i. The patrol game's ``role`` (`baselines.rl.patrol`) puts its wrapper in place of
   the env: the patrollers' parallel env, or copies of the adversary's Gymnasium env.
2. ``VecMonitor``: episode return and length, plus the task's outcome (`MONITOR_KEYS` the env
   reports), in ``info["episode"]`` and, when given a file, one CSV row per episode
   (`baselines.rl.monitor`). It sees the env's own rewards, before any normalisation.
3. ``VecNormalize`` (``normalize``): running mean/std of observations and/or of the discounted
   return, as rl-baselines3-zoo puts it (below the frame stack).
4. ``VecFrameStack`` (``n_stack`` > 1): the last n observations, concatenated.

Every layer can be captured and restored exactly (`baselines.rl.resume`): the copies of ``sync``
and ``subproc`` through `SnapshotEnv`, the others as plain objects.
"""

from __future__ import annotations

import pickle
from collections.abc import Mapping
from pathlib import Path

import gymnasium as gym

from baselines.rl.monitor import MONITOR_KEYS, open_monitor_file
from bounce_gym.errors import config_errors


class SnapshotEnv(gym.Wrapper):
    """An env whose whole state (everything it wraps) can be taken and put back, also from
    another process: what resuming a ``sync`` or ``subproc`` run restores."""

    def snapshot(self) -> bytes:
        return pickle.dumps(self.env, protocol=pickle.HIGHEST_PROTOCOL)

    def restore(self, data: bytes) -> None:
        """Put back a `snapshot` (taken by this package; read from a checkpoint's resume state
        only once that was vouched for, `baselines.rl.model_files.ModelFile.resume_state`)."""
        self.env = pickle.loads(data)  # noqa: S301


def make_config_env(config: Mapping):
    """One env of a validated configuration: a PettingZoo parallel env when its robots share the
    policy (`baselines.rl.train_config.is_multi`), a Gymnasium env otherwise."""
    from baselines.rl.train_config import is_multi

    with config_errors("config.env_kwargs"):
        if config.get("role") is not None:
            from baselines.rl.patrol import role_env

            return role_env(config["role"], dict(config["env_kwargs"]))
        if is_multi(config):
            import pettingzoo

            return pettingzoo.make("parallel", config["env"], **config["env_kwargs"])
        return gym.make(config["env"], **config["env_kwargs"])


class _CopyMaker:
    """A picklable env factory for SB3's ``SubprocVecEnv``."""

    def __init__(self, config: Mapping) -> None:
        self.config = {key: config.get(key) for key in ("env", "env_kwargs", "role")}

    def __call__(self) -> gym.Env:
        return SnapshotEnv(make_config_env(self.config))


def base_env(config: Mapping):
    """The envs of a validated configuration, unseeded, as an SB3 VecEnv (bad ``env_kwargs``
    raise `ConfigError`)."""
    from baselines.rl.train_config import is_multi

    if is_multi(config):
        from baselines.rl.parallel_vec_env import ParallelToVecEnv

        return ParallelToVecEnv(make_config_env(config))
    with config_errors("config.env_kwargs"):
        if config["vec_env"] == "native":
            from baselines.rl.vector_vec_env import VectorToVecEnv

            return VectorToVecEnv(gym.make_vec(
                config["env"], num_envs=config["n_envs"],
                vectorization_mode="vector_entry_point", **config["env_kwargs"]))
        from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

        kind = SubprocVecEnv if config["vec_env"] == "subproc" else DummyVecEnv
        return kind([_CopyMaker(config) for _ in range(config["n_envs"])])


def monitor_keys(config: Mapping) -> tuple[str, ...]:
    """The `MONITOR_KEYS` that the env of ``config`` reports in every step's ``info``."""
    from baselines.rl.train_config import is_multi

    env = make_config_env(config)
    with config_errors("config.env_kwargs"):
        env.reset(seed=0)
        if is_multi(config):
            agent = env.possible_agents[0]
            info = env.step({a: env.action_space(a).sample() for a in env.agents})[4][agent]
        else:
            info = env.step(env.action_space.sample())[4]
    env.close()
    return tuple(key for key in MONITOR_KEYS if key in info)


def make_train_env(config: Mapping, seed: int | None = None):
    """The training VecEnv of a validated configuration (module docstring), seeded with ``seed``
    (default: the first of ``config["seeds"]``) at its first reset; its monitor writes no file
    until `attach_monitor_file`."""
    from stable_baselines3.common.vec_env import VecFrameStack, VecMonitor, VecNormalize

    env = VecMonitor(base_env(config), info_keywords=monitor_keys(config))
    if config["normalize"] is not None:
        env = VecNormalize(env, gamma=config["hyperparams"].get("gamma", 0.99),
                           **config["normalize"])
    if config["n_stack"] > 1:
        env = VecFrameStack(env, config["n_stack"])
    env.seed(config["seeds"][0] if seed is None else seed)
    return env


def attach_monitor_file(env, path: Path, env_id: str, keep_rows: int | None = None) -> None:
    """Let the monitor of a training VecEnv write its episodes to ``path``: a new file, or with
    ``keep_rows`` the first ``keep_rows`` episodes of the existing one, appended to (a resumed
    run; `baselines.rl.monitor`)."""
    from stable_baselines3.common.vec_env import VecMonitor
    from stable_baselines3.common.vec_env.base_vec_env import VecEnvWrapper

    layer = env
    while not isinstance(layer, VecMonitor):
        assert isinstance(layer, VecEnvWrapper), "a training env has a VecMonitor"
        layer = layer.venv
    layer.results_writer = open_monitor_file(path, layer.t_start, env_id, layer.info_keywords,
                                             keep_rows)
