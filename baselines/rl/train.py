"""Reinforcement-learning baselines: Stable-Baselines3 agents trained on the bounce_gym envs.

A training configuration (YAML, see ``configs/train_*.yaml``)::

    name: navigation-lab             # the evaluate.py experiment the model is for
    env: bounce_gym/BounceNavigation-v0
    env_kwargs: {backend: cell, angles: [45, 90, 135]}
    algo: ppo                        # ppo | dqn | recurrentppo (sb3-contrib; memory for a robot
                                     # that senses only contact and time)
    total_timesteps: 20000
    seed: 0
    n_envs: 4                        # parallel episodes (DQN uses 1)
    vec_env: native                  # native | sync | subproc (see below)
    hyperparams: {learning_rate: 0.0003}
    checkpoint_every: 5000           # 0 = none
    tensorboard: false
    models: models                   # saved as models/<name>/<algo>_seed<seed>.zip
    torch_threads: 1                 # torch intra-op threads of this process (default 1)

Training resumes from the saved model of the same name when ``resume: true`` (an error if there
is none). Every file it writes — checkpoints (``checkpoints/<algo>_seed<seed>_<N>_steps.zip``)
and the final model — is written atomically and listed with its sha256 in its folder's
``manifest.json`` (`baselines.rl.model_files`): a crash at any instant leaves complete files only.
Mistakes (a bad key, env argument or hyperparameter, a ``name`` that is not one folder name, a
models folder that cannot be written) raise `ConfigError` before training starts.

**Batched episodes.** ``vec_env: native`` (the default for ids with a Gymnasium
``vector_entry_point``: free, navigation, coverage) steps the ``n_envs`` episodes as one batch
(`bounce_gym.envs.vector_env.BounceVectorEnv` seen through `baselines.rl.vector_vec_env`); env i
is seeded with seed + i, as SB3 seeds its copies, so it runs the same episodes as ``sync`` (SB3's
DummyVecEnv of ``gym.make`` copies, the default for the other ids) — only faster. ``subproc``
runs the copies in SB3's SubprocVecEnv. Options the batch cannot run (``step_mode: tick``, the
pymunk backend, noise) raise `ConfigError` with ``native``: choose ``sync`` for them.

**Several robots.** With a PettingZoo id (``bounce_gym/MultiBounceCoverage-v0``, …) the robots
share one policy (parameter sharing): the parallel env becomes one SB3 VecEnv with a slot per
robot (`baselines.rl.parallel_vec_env.ParallelToVecEnv`, wrapped in ``VecMonitor``), so
``n_envs`` must stay 1 and ``algo`` must be ``ppo``; ``env_kwargs`` may set ``max_cycles`` (the
episode length; see ``configs/train_multirobot_coverage.yaml``). The evaluation runs the saved
model as one policy for every robot (`baselines.rl.policies.SharedSB3Policy`); ``rl_models:
<name>`` lets several evaluation experiments (e.g. m = 2..5) use it.
"""

from __future__ import annotations

import copy
import importlib.util
from collections.abc import Mapping
from pathlib import Path

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.rl.model_files import check_folder_name, load_model, save_model
from bounce_gym.envs.registration import PETTINGZOO_ENVS, is_pettingzoo_id
from bounce_gym.errors import ConfigError, config_errors
from bounce_gym.files import check_writable

ALGOS = ("ppo", "dqn", "recurrentppo")
MULTI_ALGOS = ("ppo",)
_KEYS = {"name": str, "env": str, "env_kwargs": dict, "algo": str, "total_timesteps": int,
         "seed": int, "n_envs": int, "hyperparams": dict, "checkpoint_every": int,
         "tensorboard": bool, "models": str, "resume": bool, "vec_env": str,
         "torch_threads": int}
VEC_ENVS = ("native", "sync", "subproc")


def validate_train_config(config: object) -> dict:
    if not isinstance(config, Mapping):
        raise ConfigError(f"config: expected a mapping, got {type(config).__name__}")
    unknown = sorted(set(config) - set(_KEYS))
    if unknown:
        raise ConfigError(f"config: unknown keys {unknown}; allowed are {sorted(_KEYS)}")
    for key in ("name", "env", "algo", "total_timesteps"):
        if key not in config:
            raise ConfigError(f"config: missing key {key!r}")
    for key, kind in _KEYS.items():
        if key in config and (not isinstance(config[key], kind)
                              or kind is int and isinstance(config[key], bool)):
            raise ConfigError(f"config.{key}: expected {kind.__name__}, got "
                              f"{type(config[key]).__name__}")
    config = copy.deepcopy(dict(config))
    if config["algo"] not in ALGOS:
        raise ConfigError(f"config.algo: expected one of {ALGOS}, got {config['algo']!r}")
    multi = is_pettingzoo_id(config["env"])
    if not multi and config["env"] not in gym.registry:
        raise ConfigError(f"config.env: unknown environment id {config['env']!r}; multi-robot "
                          f"ids are {list(PETTINGZOO_ENVS)}")
    if multi and config["algo"] not in MULTI_ALGOS:
        raise ConfigError(f"config.algo: a multi-robot env trains one shared policy with one of "
                          f"{MULTI_ALGOS}, got {config['algo']!r}")
    if config.get("vec_env", "native") not in VEC_ENVS:
        raise ConfigError(f"config.vec_env: expected one of {VEC_ENVS}, got {config['vec_env']!r}")
    if multi and config.get("vec_env", "native") != "native":
        raise ConfigError("config.vec_env: a multi-robot env is one VecEnv with a slot per robot; "
                          "leave vec_env unset")
    if config.get("vec_env") == "native" and not multi \
            and gym.spec(config["env"]).vector_entry_point is None:
        raise ConfigError(f"config.vec_env: {config['env']} has no native batched env; use "
                          "'sync' or 'subproc'")
    if config["total_timesteps"] < 1:
        raise ConfigError(f"config.total_timesteps: expected an integer >= 1, got "
                          f"{config['total_timesteps']}")
    check_folder_name("config.name", config["name"])
    native = multi or gym.spec(config["env"]).vector_entry_point is not None
    defaults = {"vec_env": "native" if native else "sync", "env_kwargs": {}, "seed": 0,
                "n_envs": 1 if multi else 4, "hyperparams": {},
                "checkpoint_every": 0, "tensorboard": False, "models": "models", "resume": False,
                "torch_threads": 1}
    for key, value in defaults.items():
        config.setdefault(key, value)
    for key, least in (("n_envs", 1), ("seed", 0), ("checkpoint_every", 0),
                       ("torch_threads", 1)):
        if config[key] < least:
            raise ConfigError(f"config.{key}: expected an integer >= {least}, got {config[key]}")
    if multi and config["n_envs"] != 1:
        raise ConfigError("config.n_envs: a multi-robot env is one VecEnv with a slot per robot; "
                          "n_envs must be 1")
    return config


def make_train_env(config: Mapping):
    """The VecEnv to train on: the native batch, SB3's ``make_vec_env`` copies (``vec_env``),
    or for a PettingZoo id the
    parameter-sharing adapter (one slot per robot) under ``VecMonitor``. Bad ``env_kwargs``
    raise `ConfigError`."""
    with config_errors("config.env_kwargs"):
        return _make_train_env(config)


def _make_train_env(config: Mapping):
    if is_pettingzoo_id(config["env"]):
        import pettingzoo
        from stable_baselines3.common.vec_env import VecMonitor

        from baselines.rl.parallel_vec_env import ParallelToVecEnv

        return VecMonitor(ParallelToVecEnv(pettingzoo.make("parallel", config["env"],
                                                           **config["env_kwargs"])))
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv, VecMonitor

    n_envs = 1 if config["algo"] == "dqn" else config["n_envs"]
    if config["vec_env"] == "native":
        from baselines.rl.vector_vec_env import VectorToVecEnv

        env = VecMonitor(VectorToVecEnv(gym.make_vec(
            config["env"], num_envs=n_envs, vectorization_mode="vector_entry_point",
            **config["env_kwargs"])))
        env.seed(config["seed"])
        return env
    return make_vec_env(config["env"], n_envs=n_envs, seed=config["seed"],
                        env_kwargs=config["env_kwargs"],
                        vec_env_cls=SubprocVecEnv if config["vec_env"] == "subproc" else None)


def model_path(config: Mapping) -> Path:
    return Path(config["models"]) / config["name"] / f"{config['algo']}_seed{config['seed']}.zip"


def check_hyperparams(algo_class, hyperparams: Mapping) -> None:
    """Each hyperparameter must be an argument of the algorithm, and a number where its default
    is one (SB3 itself checks the values of some, e.g. ``n_steps``, when the model is built)."""
    import inspect

    arguments = inspect.signature(algo_class).parameters
    for key, value in hyperparams.items():
        if key not in arguments or key in ("policy", "env", "device", "seed", "verbose",
                                           "tensorboard_log"):
            raise ConfigError(f"config.hyperparams.{key}: not a hyperparameter of "
                              f"{algo_class.__name__}")
        default = arguments[key].default
        number = (int, float)
        if isinstance(default, number) and not isinstance(default, bool) and (
                not isinstance(value, number) or isinstance(value, bool)):
            raise ConfigError(f"config.hyperparams.{key}: expected a number, got {value!r}")


def train(config: Mapping, progress: bool = True) -> Path:
    """Train (or resume) an agent and save it where `evaluate.py` finds it; returns the path."""
    config = validate_train_config(config)  # the quick checks first, before importing torch
    out = model_path(config)
    check_writable("config.models", out.parent)
    if config["resume"] and not out.is_file():
        raise ConfigError(f"config.resume: no saved model {out} to resume from; train without "
                          "--resume first")
    if config["tensorboard"] and importlib.util.find_spec("tensorboard") is None:
        raise ConfigError("config.tensorboard: needs the tensorboard package "
                          "(pip install tensorboard), or set tensorboard: false")
    import torch
    from gymnasium import spaces
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import DQN, PPO

    # small MLPs on tiny batches: more intra-op threads only contend with the env processes
    torch.set_num_threads(config["torch_threads"])

    algo_class = {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}[config["algo"]]
    check_hyperparams(algo_class, config["hyperparams"])
    env = make_train_env(config)
    if config["algo"] == "dqn" and not isinstance(env.action_space, spaces.Discrete):
        raise ConfigError(f"config.algo: dqn needs discrete actions, but the env's are "
                          f"{env.action_space} (set env_kwargs.action_type: discrete, or use "
                          "ppo or recurrentppo)")
    out.parent.mkdir(parents=True, exist_ok=True)
    log_dir = str(out.parent / "tensorboard") if config["tensorboard"] else None
    if config["resume"]:
        model = load_model(out, env.observation_space, env.action_space, env=env)
        reset = False
    else:
        policy = "MlpLstmPolicy" if config["algo"] == "recurrentppo" else "MlpPolicy"
        try:
            model = algo_class(policy, env, seed=config["seed"], device="cpu", verbose=0,
                               tensorboard_log=log_dir, **config["hyperparams"])
        except (AssertionError, TypeError, ValueError) as exc:  # SB3's checks of the values
            raise ConfigError(f"config.hyperparams: {exc}") from None
        reset = True
    callbacks = []
    if config["checkpoint_every"]:
        callbacks.append(atomic_checkpoint(max(config["checkpoint_every"] // env.num_envs, 1),
                                           out.parent / "checkpoints", out.stem))
    model.learn(config["total_timesteps"], callback=callbacks or None, progress_bar=progress,
                reset_num_timesteps=reset)
    save_model(model, out)
    env.close()
    return out


def atomic_checkpoint(every: int, folder: Path, prefix: str):
    """A callback saving the model every ``every`` calls as
    ``<folder>/<prefix>_<timesteps>_steps.zip`` with `save_model` (atomic, listed in the
    manifest), where SB3's ``CheckpointCallback`` writes the zip in place."""
    from stable_baselines3.common.callbacks import BaseCallback

    class _AtomicCheckpoint(BaseCallback):
        def _on_step(self) -> bool:
            if self.n_calls % every == 0:
                save_model(self.model, folder / f"{prefix}_{self.num_timesteps}_steps.zip")
            return True

    return _AtomicCheckpoint()
