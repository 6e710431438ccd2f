"""Training configurations: keys, defaults, hyperparameter files and their checks.

A configuration is a mapping (YAML; format in `baselines.rl.train`) whose keys — type, default
and meaning — are declared once, in `TrainingConfig` (a pydantic model, from which the docs'
configuration reference and the shipped JSON Schema ``configs/schema/training.schema.json`` are
generated). `validate_train_config` checks it, merges the hyperparameter file it names and fills in the defaults, so training starts
only from a complete configuration; every mistake is a `ConfigError` naming the key.

**Hyperparameter files** (``hyperparams_file``) follow rl-baselines3-zoo's layout: one YAML file
per algorithm, keyed by env id, each entry holding the algorithm's keyword arguments plus
``n_timesteps`` (the training budget), ``n_envs``, ``policy``, ``normalize`` (VecNormalize: a
bool, or a mapping of ``norm_obs``, ``norm_reward``, ``clip_obs``, ``clip_reward``) and
``frame_stack``. Unlike rl-zoo, ``policy_kwargs`` and ``normalize`` are YAML mappings, never
Python strings to evaluate; ``activation_fn`` is a name (`ACTIVATIONS`), and ``lin_<x>`` for a
schedulable value (`SCHEDULED`) is rl-zoo's linear decay from x to 0 over training. What the
configuration sets itself wins over the file (``total_timesteps`` over ``n_timesteps``,
``n_stack`` over ``frame_stack``, each ``hyperparams`` key over the file's).

**Ranges.** Every number is checked before training starts; NaN and infinities are refused
everywhere, nested ``hyperparams`` included. ``total_timesteps`` is an integer in
[1, `MAX_TIMESTEPS` = 10**10] and ``checkpoint_every`` in [0, 10**10]; ``n_envs`` in
[1, `MAX_ENVS` = 1024]; ``n_stack`` in [1, `MAX_STACK` = 100]; ``torch_threads`` in [1, 4 x the
machine's cores]; ``seed``/``seeds`` (at most 9,000 distinct) as `baselines.seeds` allows;
``normalize``'s ``clip_obs`` and ``clip_reward`` finite and > 0. Hyperparameters
(`HYPERPARAM_RANGES`; a ``lin_<x>`` schedule is checked on x): ``learning_rate``,
``clip_range``, ``clip_range_vf`` (or null), ``target_kl`` (or null) and ``max_grad_norm``
> 0; ``gamma`` and ``tau`` in (0, 1]; ``gae_lambda``, ``exploration_fraction``,
``exploration_initial_eps`` and ``exploration_final_eps`` in [0, 1]; ``ent_coef`` and
``vf_coef`` >= 0; integers ``n_steps`` and ``batch_size`` in [1, 10**6] (and ``n_steps`` x
``n_envs``, the rollout, at most `MAX_ROLLOUT` = 10**7), ``n_epochs`` in [1, 1000],
``buffer_size`` in [1, 10**7], ``learning_starts`` in [0, 10**10], ``train_freq`` in
[1, 10**6], ``gradient_steps`` in [-1, 10**4] (-1: as many as env steps),
``target_update_interval`` in [1, 10**10], ``sde_sample_freq`` in [-1, 10**6],
``stats_window_size`` in [1, 10**6]; ``policy_kwargs.net_arch`` at most `MAX_LAYERS` = 16
layers of 1 to `MAX_WIDTH` = 4096 units (a list, or ``{pi: [...], vf: [...]}``), and
``lstm_hidden_size`` in [1, 4096], ``n_lstm_layers`` in [1, 16]. A hyperparameter without a
range here is checked for its type (`check_hyperparams`) and then by SB3.
"""

from __future__ import annotations

import copy
import math
import os
import re
from collections.abc import Mapping
from pathlib import Path
from types import NoneType, UnionType
from typing import Any, Literal, Union, get_args, get_origin

import gymnasium as gym
from pydantic import BaseModel, Field

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.config_model import ConfigModel
from baselines.rl.jaxrl.settings import hyperparameters as jax_hyperparameters
from baselines.rl.marl.settings import default_variant
from baselines.rl.marl.settings import settings as marl_settings
from baselines.rl.model_files import ALGOS, JAX_ALGOS, MARL_ALGOS, VARIANT, check_folder_name
from baselines.rl.patrol import PATROL_ID, ROLES
from baselines.seeds import TRAINING_SEEDS
from bounce_gym.documents import read_document
from bounce_gym.envs.registration import ENV_IDS, PETTINGZOO_ENVS, is_pettingzoo_id
from bounce_gym.errors import ConfigError, config_errors
from bounce_gym.files import check_path_text
from bounce_gym.validate import did_you_mean, integer, number, unknown_keys

#: the learners of a multi-robot env: SB3's PPO shared by the robots, and the multi-robot
#: learners of `baselines.rl.marl` (those on the bouncing-robot ids only)
MULTI_ALGOS = ("ppo", *MARL_ALGOS)
VEC_ENVS = ("native", "sync", "subproc")
#: The SB3 policy each algorithm trains on a flat observation, and on a ``Dict`` one (the
#: goal-conditioned envs); a hyperparameter file's ``policy`` must be one of the two.
#: (The JAX learners read the same hyperparameter file entries as their SB3 twins.)
POLICIES = {"ppo": "MlpPolicy", "dqn": "MlpPolicy", "recurrentppo": "MlpLstmPolicy",
            "jax_ppo": "MlpPolicy", "jax_dqn": "MlpPolicy", "ippo": "MlpPolicy",
            "mappo": "MlpPolicy"}
DICT_POLICIES = {"ppo": "MultiInputPolicy", "dqn": "MultiInputPolicy",
                 "recurrentppo": "MultiInputLstmPolicy", "jax_ppo": "MultiInputPolicy",
                 "jax_dqn": "MultiInputPolicy"}
#: ``replay_buffer_class`` names a hyperparameter may give (off-policy algorithms), and the
#: ``replay_buffer_kwargs`` each takes with their checks: (kind, least, most) or the choices.
REPLAY_BUFFERS = {"HerReplayBuffer": {"n_sampled_goal": (int, 1, 64),
                                      "goal_selection_strategy": ("future", "final", "episode"),
                                      "copy_info_dict": (bool,)}}
#: Hyperparameters that may be ``lin_<x>`` (linear decay from x to 0 over the run).
SCHEDULED = ("learning_rate", "clip_range", "clip_range_vf")
#: ``policy_kwargs.activation_fn`` names and the torch.nn classes they stand for.
ACTIVATIONS = {"tanh": "Tanh", "relu": "ReLU", "elu": "ELU", "leaky_relu": "LeakyReLU",
               "gelu": "GELU"}
NORMALIZE_DEFAULTS = {"norm_obs": True, "norm_reward": True, "clip_obs": 10.0,
                      "clip_reward": 10.0}
#: rl-zoo keys of a hyperparameter file entry, and the configuration keys they fill.
_FILE_KEYS = {"n_timesteps": "total_timesteps", "n_envs": "n_envs", "frame_stack": "n_stack",
              "normalize": "normalize"}
_LINEAR = re.compile(r"lin_(\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)")

#: Caps on a configuration's numbers (module docstring, "Ranges").
MAX_TIMESTEPS = 10**10
MAX_ENVS = 1024
MAX_STACK = 100
#: Most transitions of one PPO rollout (``n_steps`` x ``n_envs``).
MAX_ROLLOUT = 10**7
#: Most layers, and units per layer, of ``policy_kwargs.net_arch``.
MAX_LAYERS = 16
MAX_WIDTH = 4096
#: The range of each hyperparameter checked here: ``(integer, least, most, least excluded,
#: null allowed)``; ``most`` None is no upper bound.
HYPERPARAM_RANGES = {
    "learning_rate": (False, 0, None, True, False),
    "clip_range": (False, 0, None, True, False),
    "clip_range_vf": (False, 0, None, True, True),
    "target_kl": (False, 0, None, True, True),
    "max_grad_norm": (False, 0, None, True, False),
    "gamma": (False, 0, 1, True, False),
    "tau": (False, 0, 1, True, False),
    "gae_lambda": (False, 0, 1, False, False),
    "exploration_fraction": (False, 0, 1, False, False),
    "exploration_initial_eps": (False, 0, 1, False, False),
    "exploration_final_eps": (False, 0, 1, False, False),
    "ent_coef": (False, 0, None, False, False),
    "vf_coef": (False, 0, None, False, False),
    "n_steps": (True, 1, 10**6, False, False),
    "batch_size": (True, 1, 10**6, False, False),
    "n_epochs": (True, 1, 1000, False, False),
    "buffer_size": (True, 1, 10**7, False, False),
    "learning_starts": (True, 0, MAX_TIMESTEPS, False, False),
    "train_freq": (True, 1, 10**6, False, False),
    "gradient_steps": (True, -1, 10**4, False, False),
    "target_update_interval": (True, 1, MAX_TIMESTEPS, False, False),
    "sde_sample_freq": (True, -1, 10**6, False, False),
    "stats_window_size": (True, 1, 10**6, False, False),
}
#: The same for the sizes in ``policy_kwargs`` (`MAX_WIDTH` units, `MAX_LAYERS` layers).
_POLICY_SIZES = {"lstm_hidden_size": MAX_WIDTH, "n_lstm_layers": MAX_LAYERS}


class Normalize(ConfigModel):
    """VecNormalize's settings (``normalize: true`` is all of them at their defaults)."""

    norm_obs: bool = Field(default=NORMALIZE_DEFAULTS["norm_obs"],
                           description="Normalise the observations by their running mean and "
                                       "deviation.")
    norm_reward: bool = Field(default=NORMALIZE_DEFAULTS["norm_reward"],
                              description="Scale the rewards by the running deviation of the "
                                          "return.")
    clip_obs: float = Field(default=NORMALIZE_DEFAULTS["clip_obs"], gt=0,
                            description="Clip normalised observations to ± this.")
    clip_reward: float = Field(default=NORMALIZE_DEFAULTS["clip_reward"], gt=0,
                               description="Clip normalised rewards to ± this.")


class TrainingConfig(ConfigModel):
    """A training configuration (``bounce-gym train config.yaml``): one model per seed, saved as
    ``<models>/<name>/<algo>_seed<N>.zip``. ``validate_train_config`` checks it (the ranges of
    the module docstring) and fills in the defaults."""

    name: str = Field(description="The models' folder in the models folder (one path "
                                  "component); evaluation's rl_models names it.")
    env: str = Field(description="The registered id to train on.",
                     json_schema_extra={"enum": list(ENV_IDS)})
    env_kwargs: dict[str, Any] = Field(default_factory=dict,
                                       description="Keyword arguments of the env over the ones "
                                                   "its id registers (docs: Environments).")
    algo: str = Field(description="The learner: PPO, DQN, RecurrentPPO (sb3-contrib), the "
                                  "JAX learners, or IPPO and MAPPO on a multi-robot env.",
                      json_schema_extra={"enum": list(ALGOS)})
    variant: str | None = Field(default=None, description="A label of the run in the model "
                                                          "file names (<algo>-<variant>_seed<N>),"
                                                          " e.g. stack4: lower-case letters and "
                                                          "digits in parts joined by '-'.")
    total_timesteps: int | None = Field(
        default=None, ge=1, le=MAX_TIMESTEPS,
        description="Env steps per seed (agent-steps on a multi-robot env). Required unless "
                    "the hyperparameter file's entry gives n_timesteps.")
    seed: int | None = Field(default=None, ge=0, description="One run's seed (default 0); not "
                                                             "with seeds.")
    seeds: list[int] | None = Field(default=None, min_length=1,
                                    description="Several runs' distinct seeds (>= 0); env i of "
                                                "a run is seeded seed + i, below "
                                                f"{TRAINING_SEEDS.stop} (the training seeds).")
    n_envs: int | None = Field(default=None, ge=1, le=MAX_ENVS,
                               description="Envs stepped together (default: 4; 1 for DQN and "
                                           "ppo on a multi-robot env; teams for ippo and "
                                           "mappo, default 8).")
    n_stack: int = Field(default=1, ge=1, le=MAX_STACK, description="Frames stacked in the "
                                                                    "observation.")
    normalize: bool | Normalize = Field(default=False, description="VecNormalize: true, or its "
                                                                   "settings.")
    hyperparams_file: str | None = Field(
        default=None, description="An rl-zoo style hyperparameter file (relative: to the "
                                  "configuration file's folder); its entry for the env is "
                                  "merged in, the configuration's own keys winning.")
    hyperparams: dict[str, Any] = Field(
        default_factory=dict, description="Keyword arguments of the algorithm (ranges: docs, "
                                          "Learning); lin_<x> is a linear decay from x.")
    checkpoint_every: int = Field(default=0, ge=0, le=MAX_TIMESTEPS,
                                  description="Save a checkpoint every this many steps (0: "
                                              "never).")
    tensorboard: bool = Field(default=False, description="Write TensorBoard logs.")
    models: str = Field(default="models", description="The folder of the models' folders.")
    resume: bool = Field(default=False, description="Continue the seeds from their checkpoints "
                                                    "(also the flag --resume).")
    vec_env: Literal[VEC_ENVS] | None = Field(  # type: ignore[valid-type]
        default=None, description="How the envs are stepped: native (the env's own batched "
                                  "version, the default where there is one), sync or subproc.")
    torch_threads: int = Field(default=1, ge=1, description="Threads torch may use (at most 4 "
                                                            "per core).")
    role: Literal[ROLES] | None = Field(  # type: ignore[valid-type]
        default=None, description=f"Which side of {PATROL_ID} to train (only there).")


def _kinds(annotation: object) -> tuple[type, ...]:
    """The Python types a value of a `TrainingConfig` field may have (a model: a mapping)."""
    out: list[type] = []
    members = get_args(annotation) if get_origin(annotation) in (Union, UnionType) \
        else (annotation,)
    for member in members:
        origin = get_origin(member) or member
        if origin is Literal:
            out.extend(type(value) for value in get_args(member))
        elif isinstance(origin, type) and issubclass(origin, BaseModel):
            out.append(dict)
        elif origin is not NoneType:
            out.append(origin)
    return tuple(dict.fromkeys(out))


#: each key's types (`TrainingConfig`)
_KEYS = {key: _kinds(field.annotation) for key, field in TrainingConfig.model_fields.items()}
#: the defaults filled in whatever the configuration (the others depend on it, or stay unset)
_DEFAULTS = {"variant": None, **{
    key: field.get_default(call_default_factory=True)
    for key, field in TrainingConfig.model_fields.items()
    if not field.is_required() and field.get_default(call_default_factory=True) is not None}}


def _kind_name(kind: tuple[type, ...]) -> str:
    return " or ".join(k.__name__ for k in kind)


def _is_kind(value: object, kind: tuple[type, ...]) -> bool:
    return isinstance(value, kind) and not (kind == (int,) and isinstance(value, bool))


def _check_types(config: Mapping) -> None:
    """Each key's value is of its type; a value of the wrong type that fits a key of a close
    name (``seed: [1, 2]`` for ``seeds``) names that key too (`did_you_mean`)."""
    for key, kind in _KEYS.items():
        value = config.get(key)
        if key in config and not _is_kind(value, kind):
            fitting = [other for other, other_kind in _KEYS.items()
                       if other not in config and _is_kind(value, other_kind)]
            hint = did_you_mean([key], fitting)
            raise ConfigError(f"config.{key}: expected {_kind_name(kind)}, got "
                              f"{type(value).__name__}{f' ({hint})' if hint else ''}")


def validate_train_config(config: object, folder: Path | None = None) -> dict:
    """The checked, complete configuration: the hyperparameter file merged in (a relative
    ``hyperparams_file`` is read from ``folder``, the configuration file's folder, or the
    current one), defaults filled in, ``seed``/``seeds`` turned into the list ``seeds``."""
    if not isinstance(config, Mapping):
        raise ConfigError(f"config: expected a mapping, got {type(config).__name__}")
    unknown_keys("config", config, _KEYS)
    for key in ("name", "env", "algo"):
        if key not in config:
            raise ConfigError(f"config: missing key {key!r}")
    _check_types(config)
    config = copy.deepcopy(dict(config))
    if config["algo"] not in ALGOS:
        raise ConfigError(f"config.algo: expected one of {ALGOS}, got {config['algo']!r}")
    _check_role(config)
    multi = is_multi(config)
    if config["env"] not in ENV_IDS:
        raise ConfigError(f"config.env: unknown environment id {config['env']!r}; registered: "
                          f"{list(ENV_IDS)}")
    if "hyperparams_file" in config:
        _merge_file(config, folder)
        _check_types(config)
    if "total_timesteps" not in config:
        raise ConfigError("config: missing key 'total_timesteps' (or n_timesteps in the "
                          "hyperparams_file entry)")
    if multi and config["algo"] not in MULTI_ALGOS:
        raise ConfigError(f"config.algo: a multi-robot env trains with one of {MULTI_ALGOS}, "
                          f"got {config['algo']!r}")
    if config["algo"] in MARL_ALGOS:
        _check_marl(config)
    native = multi or "role" not in config and \
        gym.spec(config["env"]).vector_entry_point is not None
    if config["algo"] in JAX_ALGOS:
        _check_jax(config, multi)
    _check_vec_env(config, multi, native)
    integer("config.total_timesteps", config["total_timesteps"], 1, MAX_TIMESTEPS)
    check_folder_name("config.name", config["name"])
    if "variant" in config and not VARIANT.fullmatch(config["variant"]):
        raise ConfigError(f"config.variant: expected lower-case letters and digits in parts "
                          f"joined by '-' (e.g. stack4), got {config['variant']!r}")
    defaults = {"n_envs": MARL_TEAMS if config["algo"] in MARL_ALGOS
                else 1 if multi or config["algo"] in ("dqn", "jax_dqn") else 4, **_DEFAULTS}
    if config["algo"] in MARL_ALGOS:
        defaults["variant"] = default_variant(config.get("hyperparams", {}))
    for key, value in defaults.items():
        config.setdefault(key, value)
    check_path_text("config.models", config["models"])
    for key, least, most in (("n_envs", 1, MAX_ENVS), ("n_stack", 1, MAX_STACK),
                             ("checkpoint_every", 0, MAX_TIMESTEPS),
                             ("torch_threads", 1, 4 * (os.cpu_count() or 1))):
        integer(f"config.{key}", config[key], least, most)
    config["seeds"] = _seeds(config)
    config.pop("seed", None)
    config["normalize"] = _normalize(config["normalize"])
    if multi:
        _check_multi(config)
    _check_seed_range(config)
    _check_schedules(config["hyperparams"])
    _check_finite("config.hyperparams", config["hyperparams"])
    for key, value in config["hyperparams"].items():
        check_range(f"config.hyperparams.{key}", key, value)
    rollout = config["hyperparams"].get("n_steps", 0) * config["n_envs"]
    if rollout > MAX_ROLLOUT:
        raise ConfigError(f"config.hyperparams.n_steps: n_steps x n_envs is a rollout of "
                          f"{rollout} transitions; at most {MAX_ROLLOUT} are allowed")
    _check_policy_kwargs(config["hyperparams"])
    _check_replay_buffer(config["hyperparams"])
    if config["algo"] in JAX_ALGOS:
        jax_hyperparameters(config["algo"], config["hyperparams"])
    if config["algo"] in MARL_ALGOS:
        marl_settings(config["hyperparams"], config["n_envs"])
    # last: asking the batched env builds an env (heavy imports), after every cheap check
    config.setdefault("vec_env", "native" if native and (multi or _batched(config)) else "sync")
    return config


#: The teams (``n_envs``) of ippo and mappo when neither the configuration nor its
#: hyperparameter file says.
MARL_TEAMS = 8
#: Keys of a configuration the multi-robot learners do not honour, with the value they need.
_MARL_FIXED = {"tensorboard": False, "resume": False}


def _check_marl(config: dict) -> None:
    """ippo and mappo (`baselines.rl.marl`) train the bouncing robots of a PettingZoo id on
    the batched team env: no TensorBoard, no resuming (their checkpoints hold weights only)."""
    algo = config["algo"]
    if config["env"] not in PETTINGZOO_ENVS:
        raise ConfigError(f"config.env: {algo} trains the robots of one of "
                          f"{sorted(PETTINGZOO_ENVS)} (the batched team env), not "
                          f"{config['env']}")
    _refuse_fixed(config, _MARL_FIXED, "the multi-robot learners",
                  "not the optimiser, the generator or the teams mid-episode")


#: Keys of a configuration the JAX learners do not honour, each with the value they need.
_JAX_FIXED = {"n_stack": 1, "normalize": False, "tensorboard": False, "resume": False}


def _check_jax(config: dict, multi: bool) -> None:
    """The JAX learners (`baselines.rl.jaxrl`) train one robot on the functional env itself:
    no VecEnv, wrappers, tensorboard or resuming (`baselines.rl.jaxrl.runner` says why)."""
    algo = config["algo"]
    if multi or "role" in config:
        raise ConfigError(f"config.algo: {algo} trains single-robot envs; use ppo here")
    if "vec_env" in config:
        raise ConfigError(f"config.vec_env: {algo} steps its envs in JAX; remove the key")
    _refuse_fixed(config, _JAX_FIXED, "the JAX learners",
                  "the optimiser, key, envs and replay buffer live on the device")


def _refuse_fixed(config: dict, fixed: dict, learners: str, kept_out: str) -> None:
    """A `ConfigError` for the first key of ``fixed`` the configuration sets otherwise than to
    its value: ``resume`` says what the weights-only checkpoints leave out (``kept_out``), any
    other key that ``learners`` do not support it."""
    for key, value in fixed.items():
        if config.get(key, value) != value:
            why = (f"its checkpoints hold weights only ({kept_out}); train again without "
                   "resume") if key == "resume" else f"not supported by {learners}; remove the key"
            raise ConfigError(f"config.{key}: {config['algo']}: {why}")


def policy_name(algo: str, observation_space) -> str:
    """The SB3 policy ``algo`` trains on ``observation_space`` (`POLICIES`, `DICT_POLICIES`)."""
    return (DICT_POLICIES if isinstance(observation_space, gym.spaces.Dict) else POLICIES)[algo]


def _check_replay_buffer(hyperparams: dict) -> None:
    """``replay_buffer_class`` is a name of `REPLAY_BUFFERS`; ``replay_buffer_kwargs`` only
    with it, each key of its table in range."""
    field = "config.hyperparams"
    name = hyperparams.get("replay_buffer_class")
    kwargs = hyperparams.get("replay_buffer_kwargs")
    if name is None:
        if kwargs is not None:
            raise ConfigError(f"{field}.replay_buffer_kwargs: only with replay_buffer_class")
        return
    if name not in REPLAY_BUFFERS:
        raise ConfigError(f"{field}.replay_buffer_class: expected one of "
                          f"{sorted(REPLAY_BUFFERS)}, got {name!r}")
    if kwargs is None:
        return
    if not isinstance(kwargs, dict):
        raise ConfigError(f"{field}.replay_buffer_kwargs: expected a mapping, got {kwargs!r}")
    table = REPLAY_BUFFERS[name]
    for key, value in kwargs.items():
        check = table.get(key)
        where = f"{field}.replay_buffer_kwargs.{key}"
        if check is None:
            raise ConfigError(f"{where}: not an argument of {name}; allowed are {sorted(table)}")
        if check[0] is int:
            integer(where, value, check[1], check[2])
        elif check[0] is bool:
            if not isinstance(value, bool):
                raise ConfigError(f"{where}: expected true or false, got {value!r}")
        elif value not in check:
            raise ConfigError(f"{where}: expected one of {list(check)}, got {value!r}")


def is_multi(config: Mapping) -> bool:
    """Whether ``config`` trains one policy shared by several robots (a PettingZoo id, except
    the adversary of Patrol-v0, which is one agent)."""
    return is_pettingzoo_id(config["env"]) and config.get("role") != "adversary"


def _check_role(config: Mapping) -> None:
    """``role`` is what a configuration of the patrol game trains (`baselines.rl.patrol`): its
    patrollers or its adversary; no other env has roles."""
    role = config.get("role")
    if config["env"] == PATROL_ID and role not in ROLES:
        raise ConfigError(f"config.role: {PATROL_ID} is a game of two sides; expected one of "
                          f"{ROLES} (baselines.rl.patrol), got {role!r}")
    if config["env"] != PATROL_ID and role is not None:
        raise ConfigError(f"config.role: only {PATROL_ID} has roles, not {config['env']}; "
                          "remove the key")


def _batched(config: Mapping) -> bool:
    """Whether the env's batched version steps ``env_kwargs`` (an id with one): not the pymunk
    backend, actuation noise or tick steps (`bounce_gym.envs.vector_env.batch_refusal`), which
    train on ``sync`` copies by default. Bad ``env_kwargs`` raise `ConfigError` here."""
    from bounce_gym.envs.vector_env import batch_refusal

    if "vec_env" in config:
        return config["vec_env"] == "native"
    options = {**gym.spec(config["env"]).kwargs, **config.get("env_kwargs", {})}
    with config_errors("config.env_kwargs"):
        return batch_refusal(**options) is None


def _check_vec_env(config: dict, multi: bool, native: bool) -> None:
    if config.get("vec_env", "native") not in VEC_ENVS:
        raise ConfigError(f"config.vec_env: expected one of {VEC_ENVS}, got {config['vec_env']!r}")
    if multi and config.get("vec_env", "native") != "native":
        raise ConfigError("config.vec_env: a multi-robot env is one VecEnv with a slot per robot; "
                          "leave vec_env unset")
    if config.get("vec_env") == "native" and not native:
        raise ConfigError(f"config.vec_env: {config['env']} has no native batched env; use "
                          "'sync' or 'subproc'")


def _check_multi(config: dict) -> None:
    if config["algo"] == "ppo" and config["n_envs"] != 1:
        raise ConfigError("config.n_envs: a multi-robot env is one VecEnv with a slot per robot; "
                          "n_envs must be 1")
    if config["n_stack"] != 1 or config["normalize"] is not None:
        key = "n_stack" if config["n_stack"] != 1 else "normalize"
        raise ConfigError(f"config.{key}: frame stacking and VecNormalize are for single-robot "
                          "envs; the shared multi-robot policy runs without them")


def _seeds(config: dict) -> list[int]:
    if "seed" in config and "seeds" in config:
        raise ConfigError("config.seeds: give either seed (one run) or seeds (several), not both")
    if "seeds" not in config:
        seed = config.get("seed", 0)
        if seed < 0:
            raise ConfigError(f"config.seed: expected an integer >= 0, got {seed}")
        return [seed]
    seeds = config["seeds"]
    if not seeds or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0
                            for s in seeds) or len(set(seeds)) != len(seeds):
        raise ConfigError(f"config.seeds: expected a non-empty list of distinct integers >= 0, "
                          f"got {seeds!r}")
    return list(seeds)


def _check_seed_range(config: dict) -> None:
    """Env i of the run with seed s is seeded with s + i: every such seed is a training seed,
    below the tuning and evaluation seeds (`baselines.seeds`)."""
    for seed in config["seeds"]:
        if seed + config["n_envs"] > TRAINING_SEEDS.stop:
            raise ConfigError(
                f"config.seeds: seed {seed} with n_envs {config['n_envs']} would seed envs up to "
                f"{seed + config['n_envs'] - 1}; training env seeds must stay below "
                f"{TRAINING_SEEDS.stop}, where the tuning seeds start (baselines.seeds)")


def _normalize(value: bool | dict) -> dict | None:
    """The VecNormalize settings (``None``: no VecNormalize)."""
    if value is False:
        return None
    settings = dict(NORMALIZE_DEFAULTS)
    if isinstance(value, dict):
        unknown_keys("config.normalize", value, NORMALIZE_DEFAULTS)
        for key, default in NORMALIZE_DEFAULTS.items():
            item = value.get(key, default)
            if isinstance(default, float):
                settings[key] = number(f"config.normalize.{key}", item, minimum=0, strict=True)
            elif not isinstance(item, bool):
                raise ConfigError(f"config.normalize.{key}: expected true or false, got "
                                  f"{item!r}")
            else:
                settings[key] = item
    if not settings["norm_obs"] and not settings["norm_reward"]:
        return None
    return settings


def _check_schedules(hyperparams: dict) -> None:
    for key, value in hyperparams.items():
        if isinstance(value, str) and value.startswith("lin_"):
            if key not in SCHEDULED:
                raise ConfigError(f"config.hyperparams.{key}: a lin_ schedule is allowed only "
                                  f"for {SCHEDULED}")
            if not _LINEAR.fullmatch(value):
                raise ConfigError(f"config.hyperparams.{key}: expected lin_<number>, got "
                                  f"{value!r}")


def _check_policy_kwargs(hyperparams: dict) -> None:
    policy_kwargs = hyperparams.get("policy_kwargs", {})
    if not isinstance(policy_kwargs, dict):
        raise ConfigError(f"config.hyperparams.policy_kwargs: expected a mapping, got "
                          f"{policy_kwargs!r}")
    name = policy_kwargs.get("activation_fn", "tanh")
    if name not in ACTIVATIONS:
        raise ConfigError(f"config.hyperparams.policy_kwargs.activation_fn: expected one of "
                          f"{sorted(ACTIVATIONS)}, got {name!r}")
    field = "config.hyperparams.policy_kwargs"
    for key, most in _POLICY_SIZES.items():
        if key in policy_kwargs:
            integer(f"{field}.{key}", policy_kwargs[key], 1, most)
    if "net_arch" in policy_kwargs:
        arch = policy_kwargs["net_arch"]
        if isinstance(arch, dict):
            unknown_keys(f"{field}.net_arch", arch, ("pi", "vf", "qf"))
            for key, layers in arch.items():
                _check_layers(f"{field}.net_arch.{key}", layers)
        else:
            _check_layers(f"{field}.net_arch", arch)


def _check_layers(field: str, layers: object) -> None:
    if not isinstance(layers, list) or len(layers) > MAX_LAYERS:
        raise ConfigError(f"{field}: expected a list of at most {MAX_LAYERS} layer sizes, got "
                          f"{layers!r}")
    for k, width in enumerate(layers):
        integer(f"{field}[{k}]", width, 1, MAX_WIDTH)


def check_range(field: str, key: str, value: object) -> None:
    """Raise `ConfigError` naming ``field`` unless ``value`` is within the documented range of
    hyperparameter ``key`` (`HYPERPARAM_RANGES`; a ``lin_<x>`` schedule is checked on x, a
    hyperparameter without a range passes)."""
    if key not in HYPERPARAM_RANGES:
        return
    whole, least, most, excluded, nullable = HYPERPARAM_RANGES[key]
    if value is None and nullable:
        return
    if isinstance(value, str) and key in SCHEDULED and _LINEAR.fullmatch(value):
        value = float(_LINEAR.fullmatch(value).group(1))
        field = f"{field} (the start of its lin_ schedule)"
    if whole:
        integer(field, value, least, most)
    else:
        number(field, value, minimum=least, strict=excluded, maximum=most)


def _check_finite(field: str, value: object) -> None:
    """No NaN or infinity anywhere in ``value`` (nested mappings and lists included)."""
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(f"{field}: expected a finite number, got {value!r}")
    if isinstance(value, dict):
        for key, item in value.items():
            _check_finite(f"{field}.{key}", item)
    elif isinstance(value, list):
        for k, item in enumerate(value):
            _check_finite(f"{field}[{k}]", item)


def _merge_file(config: dict, folder: Path | None) -> None:
    """Merge the ``config["env"]`` entry of the hyperparameter file into ``config`` (for the
    patrol game, ``<env>:<role>``: each side is a training problem of its own)."""
    path = Path(config["hyperparams_file"])
    if not path.is_absolute():
        path = (folder or Path.cwd()) / path
    config["hyperparams_file"] = str(path)
    field = "config.hyperparams_file"
    entries = read_document(path, field)
    key = config["env"] if "role" not in config else f"{config['env']}:{config['role']}"
    if not isinstance(entries, dict) or key not in entries:
        ids = sorted(entries) if isinstance(entries, dict) else []
        raise ConfigError(f"{field}: {path} has no entry for {key}; it has {ids}")
    entry = entries[key]
    if not isinstance(entry, dict):
        raise ConfigError(f"{field}: the entry {key} of {path} is not a mapping")
    entry = dict(entry)
    algo = config["algo"]
    policy = entry.pop("policy", POLICIES[algo])
    if policy not in (POLICIES[algo], DICT_POLICIES.get(algo)):
        on_dict = f" (or {DICT_POLICIES[algo]!r} on a Dict observation)" \
            if algo in DICT_POLICIES else ""
        raise ConfigError(f"{field}: {key} names policy {policy!r}, but {algo} trains "
                          f"{POLICIES[algo]!r}{on_dict}")
    timesteps = entry.get("n_timesteps")
    if isinstance(timesteps, float) and timesteps.is_integer():  # rl-zoo writes !!float 1e5
        entry["n_timesteps"] = int(timesteps)
    for file_key, key in _FILE_KEYS.items():
        if file_key in entry:
            config.setdefault(key, entry.pop(file_key))
    config["hyperparams"] = {**entry, **config.get("hyperparams", {})}


def algo_class(algo: str):
    """The Stable-Baselines3 (or sb3-contrib) class of an algorithm of `ALGOS`."""
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import DQN, PPO

    return {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}[algo]


def check_hyperparams(algo_class, hyperparams: Mapping) -> None:
    """Each hyperparameter must be an argument of the algorithm, and a number where its default
    is one (a ``lin_`` schedule where `SCHEDULED` allows it); SB3 itself checks the values of
    some, e.g. ``n_steps``, when the model is built."""
    import inspect

    arguments = inspect.signature(algo_class).parameters
    fixed = ("policy", "env", "device", "seed", "verbose", "tensorboard_log")
    for key, value in hyperparams.items():
        if key not in arguments or key in fixed:
            hint = did_you_mean([key], [name for name in arguments if name not in fixed])
            raise ConfigError(f"config.hyperparams.{key}: not a hyperparameter of "
                              f"{algo_class.__name__}{f' ({hint})' if hint else ''}")
        default = arguments[key].default
        number = (int, float)
        scheduled = isinstance(value, str) and value.startswith("lin_")  # _check_schedules
        if isinstance(default, number) and not isinstance(default, bool) and not scheduled and (
                not isinstance(value, number) or isinstance(value, bool)):
            raise ConfigError(f"config.hyperparams.{key}: expected a number, got {value!r}")


def algo_kwargs(hyperparams: Mapping) -> dict:
    """The SB3 keyword arguments of the validated ``hyperparams``: ``lin_<x>`` becomes a linear
    schedule, ``policy_kwargs.activation_fn`` and ``replay_buffer_class`` the classes they
    name."""
    from stable_baselines3.common.utils import LinearSchedule
    from torch import nn

    kwargs = copy.deepcopy(dict(hyperparams))
    for key in SCHEDULED:
        value = kwargs.get(key)
        if isinstance(value, str):
            kwargs[key] = LinearSchedule(float(_LINEAR.fullmatch(value).group(1)), 0.0, 1.0)
    policy_kwargs = kwargs.get("policy_kwargs")
    if policy_kwargs and "activation_fn" in policy_kwargs:
        policy_kwargs["activation_fn"] = getattr(nn, ACTIVATIONS[policy_kwargs["activation_fn"]])
    if "replay_buffer_class" in kwargs:
        import stable_baselines3

        kwargs["replay_buffer_class"] = getattr(stable_baselines3, kwargs["replay_buffer_class"])
    return kwargs
