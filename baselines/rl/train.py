"""Reinforcement-learning baselines: Stable-Baselines3 agents trained on the bounce_gym envs.

A training configuration (YAML, see ``configs/train_*.yaml``)::

    name: navigation-lab             # the evaluate.py experiment the model is for
    env: bounce_gym/BounceNavigation-v0
    env_kwargs: {backend: cell, angles: [45, 90, 135]}
    algo: ppo                        # ppo | dqn | recurrentppo (sb3-contrib; memory for a robot
                                     # that senses only contact and time)
    total_timesteps: 20000
    seed: 0
    n_envs: 4                        # SB3 DummyVecEnv copies (DQN uses 1)
    hyperparams: {learning_rate: 0.0003}
    checkpoint_every: 5000           # 0 = none
    tensorboard: false
    models: models                   # saved as models/<name>/<algo>_seed<seed>.zip

Training resumes from the checkpoint of the same name when ``resume: true``.

**Several robots.** With a PettingZoo id (``bounce_gym/MultiBounceCoverage-v0``, …) the robots
share one policy (parameter sharing): the parallel env becomes one SB3 VecEnv with a slot per
robot (`baselines.rl.parallel_vec_env.ParallelToVecEnv`, wrapped in ``VecMonitor``), so ``n_envs`` must stay 1
and ``algo`` must be ``ppo``; ``env_kwargs`` may set ``max_cycles`` (the episode length; see
``configs/train_multirobot_coverage.yaml``). `experiments.multi_evaluation` runs the saved model
as one shared policy for every robot; ``rl_models: <name>`` lets several evaluation experiments
(e.g. m = 2..5) use it.
"""

from __future__ import annotations

import copy
import importlib.util
from collections.abc import Mapping
from pathlib import Path

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.envs.registration import PETTINGZOO_ENVS
from bounce_gym.errors import ConfigError

ALGOS = ("ppo", "dqn", "recurrentppo")
MULTI_ALGOS = ("ppo",)
_KEYS = {"name": str, "env": str, "env_kwargs": dict, "algo": str, "total_timesteps": int,
         "seed": int, "n_envs": int, "hyperparams": dict, "checkpoint_every": int,
         "tensorboard": bool, "models": str, "resume": bool}


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
    multi = config["env"] in PETTINGZOO_ENVS
    if not multi and config["env"] not in gym.registry:
        raise ConfigError(f"config.env: unknown environment id {config['env']!r}; multi-robot "
                          f"ids are {list(PETTINGZOO_ENVS)}")
    if multi and config["algo"] not in MULTI_ALGOS:
        raise ConfigError(f"config.algo: a multi-robot env trains one shared policy with one of "
                          f"{MULTI_ALGOS}, got {config['algo']!r}")
    if config["total_timesteps"] < 1:
        raise ConfigError("config.total_timesteps: expected an integer >= 1")
    defaults = {"env_kwargs": {}, "seed": 0, "n_envs": 1 if multi else 4, "hyperparams": {},
                "checkpoint_every": 0, "tensorboard": False, "models": "models", "resume": False}
    for key, value in defaults.items():
        config.setdefault(key, value)
    if config["n_envs"] < 1:
        raise ConfigError("config.n_envs: expected an integer >= 1")
    if multi and config["n_envs"] != 1:
        raise ConfigError("config.n_envs: a multi-robot env is one VecEnv with a slot per robot; "
                          "n_envs must be 1")
    return config


def make_train_env(config: Mapping):
    """The VecEnv to train on: SB3's ``make_vec_env`` copies, or for a PettingZoo id the
    parameter-sharing adapter (one slot per robot) under ``VecMonitor``."""
    if config["env"] in PETTINGZOO_ENVS:
        import pettingzoo
        from stable_baselines3.common.vec_env import VecMonitor

        from baselines.rl.parallel_vec_env import ParallelToVecEnv

        return VecMonitor(ParallelToVecEnv(pettingzoo.make("parallel", config["env"],
                                                           **config["env_kwargs"])))
    from stable_baselines3.common.env_util import make_vec_env

    n_envs = 1 if config["algo"] == "dqn" else config["n_envs"]
    return make_vec_env(config["env"], n_envs=n_envs, seed=config["seed"],
                        env_kwargs=config["env_kwargs"])


def model_path(config: Mapping) -> Path:
    return Path(config["models"]) / config["name"] / f"{config['algo']}_seed{config['seed']}.zip"


def train(config: Mapping, progress: bool = True) -> Path:
    """Train (or resume) an agent and save it where `evaluate.py` finds it; returns the path."""
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.callbacks import CheckpointCallback

    config = validate_train_config(config)
    algo_class = {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}[config["algo"]]
    env = make_train_env(config)
    out = model_path(config)
    out.parent.mkdir(parents=True, exist_ok=True)
    log_dir = str(out.parent / "tensorboard") if config["tensorboard"] else None
    if log_dir is not None and importlib.util.find_spec("tensorboard") is None:
        raise ConfigError("config.tensorboard: needs the tensorboard package "
                          "(pip install tensorboard), or set tensorboard: false")
    if config["resume"] and out.is_file():
        model = algo_class.load(out, env=env, device="cpu")
        reset = False
    else:
        policy = "MlpLstmPolicy" if config["algo"] == "recurrentppo" else "MlpPolicy"
        try:
            model = algo_class(policy, env, seed=config["seed"], device="cpu", verbose=0,
                               tensorboard_log=log_dir, **config["hyperparams"])
        except TypeError as exc:
            raise ConfigError(f"config.hyperparams: {exc}") from None
        reset = True
    callbacks = []
    if config["checkpoint_every"]:
        callbacks.append(CheckpointCallback(max(config["checkpoint_every"] // env.num_envs, 1),
                                            str(out.parent / "checkpoints"),
                                            name_prefix=out.stem))
    model.learn(config["total_timesteps"], callback=callbacks or None, progress_bar=progress,
                reset_num_timesteps=reset)
    tmp = out.with_name(out.stem + ".partial.zip")
    model.save(tmp)
    tmp.replace(out)  # atomic: evaluate.py never loads a half-written model
    env.close()
    return out
