"""Evaluation configurations: loading YAML, the default configuration, and validation.

Every key, its type, default and meaning is declared once, in the models below
(`EvaluationConfig`, `Experiment`, `SeedRange`, `ModelFolder`, `ExecutorSettings`); the docs'
configuration reference and the shipped JSON Schema (``configs/schema/evaluation.schema.json``,
`bounce_gym_experiments.schema`) are generated from them. A configuration lists *experiments*;
each names a registered environment id (Gymnasium or PettingZoo) with overrides, the seeds, and
which kinds of policy to run. The experiment's family (`bounce_gym_experiments.registry`) owns
the checks of its own keys: which ``policies`` it runs and their default, ``adversaries``,
``planner_kwargs``, ``visibility`` (`bounce_gym_experiments.families.base.Family.validate`).

**Seeds.** Evaluation seeds are disjoint from the training and tuning seeds
(`baselines.seeds`): every seed must be at least ``EVALUATION_SEEDS_START`` (10,000) and at
most `MAX_SEED` (2**32 - 1), and one that falls in a reserved range is refused naming it; at
most `MAX_SEEDS` (100,000) of them; the validated configuration holds the list.

**Horizon.** An episode lasts at most the horizon its env registers — Gymnasium's
``max_episode_steps``, PettingZoo's ``max_cycles``; for the ids whose horizon follows from their
map (`bounce_gym.envs.registration.MAP_HORIZON`) the one the env derives on the experiment's
map — which is also what training uses; a
different ``max_steps`` (at most `MAX_STEPS`) needs ``horizon_reason``, and then sets the env's
own limit, so that the env and the episode loop stop together.

**Env arguments.** Each experiment's env is built once while the configuration is checked
(`env_horizon`, which also reads its horizon off it), before the experiment families and their
heavy imports (SciPy, the RL libraries) are loaded: a bad ``env_kwargs`` fails as fast as a bad
key of the document.

A relative map file in ``env_kwargs.world`` (``*.yaml``, ``*.yml``, ``*.json``) or flow file
in ``env_kwargs.flow`` (a path with a suffix, e.g. ``*.nc``; zoo names have none) of a
configuration file is read relative to that file's folder.

The default configuration is the packaged ``eval_default.yaml`` (the top-level ``configs/``
folder of a source checkout, ``bounce_gym_experiments/configs/`` once installed).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import gymnasium as gym
import pettingzoo
from pydantic import Field, ValidationInfo, field_validator, model_validator

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.config_model import ConfigModel, located, shorten, where
from baselines.rl.model_files import check_folder_name
from baselines.seeds import EVALUATION_SEEDS_START, MAX_SEED, reserved_overlap
from baselines.shipped_agents import models_folder
from bounce_gym.documents import read_document
from bounce_gym.envs.registration import ENV_IDS, MAP_HORIZON, is_pettingzoo_id
from bounce_gym.errors import ConfigError, config_errors
from bounce_gym.files import check_path_component, check_path_text
from bounce_gym.validate import integer
from bounce_gym_experiments.executors import (
    EXECUTOR_DEFAULTS,
    EXECUTOR_KINDS,
    MAX_RETRIES,
    MAX_WORKERS,
    executor_settings,
)

DIFFICULTIES = ("easy", "medium", "hard")
DEFAULT_CONFIG_NAME = "eval_default.yaml"
#: Most evaluation seeds of one experiment (episodes per policy).
MAX_SEEDS = 100_000
#: Longest episode an experiment's ``max_steps`` may ask for.
MAX_STEPS = 10**6
#: env options a model folder of ``rl_models`` may set differently (observation only)
OBSERVATION_OPTIONS = frozenset({"privileged", "history", "agent_id"})
_MAP_SUFFIXES = (".yaml", ".yml", ".json")
#: env options no experiment sets: its horizon is ``max_steps``
_HORIZON_OPTIONS = ("max_episode_steps", "max_cycles")
#: the description of ``env_kwargs`` (`bounce_gym_experiments.schema` plugs in each env's own)
ENV_KWARGS_DESCRIPTION = (
    "Keyword arguments of the env (gym.make / pettingzoo.make) over the ones its id registers: "
    "the env's options (docs: Environments). A relative map file (world: *.yaml, *.yml, *.json) "
    "or flow file (flow: a path with a suffix) is read from the configuration file's folder. "
    "Neither max_episode_steps nor max_cycles: the horizon is max_steps.")


class SeedRange(ConfigModel):
    """``{start, count}``: the seeds start, start + 1, …, start + count - 1."""

    start: int = Field(ge=EVALUATION_SEEDS_START, le=MAX_SEED,
                       description=f"The first seed (at least {EVALUATION_SEEDS_START}: the "
                                   f"seeds below are training's and tuning's).")
    count: int = Field(ge=1, le=MAX_SEEDS, description="How many seeds (at most 100000, and the "
                                                       "last at most 2**32 - 1).")

    @model_validator(mode="before")
    @classmethod
    def _range(cls, data: Any, info: ValidationInfo) -> Any:
        if isinstance(data, Mapping) and isinstance(data.get("start"), int) \
                and isinstance(data.get("count"), int):  # else pydantic's type error
            reserved = reserved_overlap(range(data["start"], data["start"] + data["count"]))
            if reserved is not None:
                raise ConfigError(f"{where(info)}: evaluation seeds must not overlap {reserved} "
                                  f"(baselines.seeds), got start {data['start']}, count "
                                  f"{data['count']}")
            start = integer(located(info, "start"), data["start"],
                            minimum=EVALUATION_SEEDS_START, maximum=MAX_SEED)
            integer(located(info, "count"), data["count"], minimum=1,
                    maximum=min(MAX_SEEDS, MAX_SEED - start + 1))
        return data


class ModelFolder(ConfigModel):
    """A folder of trained models to evaluate, with the observation options its models were
    trained with where they differ from the experiment's."""

    folder: str = Field(description="The folder's name in the models folder (one path "
                                    "component).")
    env_kwargs: dict[str, Any] = Field(
        default_factory=dict,
        description=f"Observation options set over the experiment's env_kwargs for these "
                    f"models: only {sorted(OBSERVATION_OPTIONS)}, so the episodes stay the same.")

    @field_validator("folder")
    @classmethod
    def _folder(cls, value: str, info: ValidationInfo) -> str:
        check_folder_name(located(info), value)
        return value

    @field_validator("env_kwargs")
    @classmethod
    def _observation_only(cls, value: dict, info: ValidationInfo) -> dict:
        if set(value) - OBSERVATION_OPTIONS:
            raise ConfigError(f"{located(info)}: only observation options "
                              f"{sorted(OBSERVATION_OPTIONS)} may differ from the experiment's, "
                              f"got {sorted(set(value) - OBSERVATION_OPTIONS)}")
        return value


class ExecutorSettings(ConfigModel):
    """Where the evaluation's units run (`bounce_gym_experiments.executors`, whose
    `executor_settings` checks it, the flags' values too); the flags
    ``--executor``, ``--workers`` and ``--address`` override it. It does not change the
    results."""

    kind: Literal[EXECUTOR_KINDS] = Field(  # type: ignore[valid-type]
        default=EXECUTOR_DEFAULTS["kind"],
        description="local: a process pool on this machine; ray: a Ray cluster.")
    workers: int | None = Field(default=EXECUTOR_DEFAULTS["workers"], ge=1, le=MAX_WORKERS,
                                description="Units at once (default: the machine's cores).")
    address: str | None = Field(default=EXECUTOR_DEFAULTS["address"],
                                description="The Ray cluster (auto, host:port or "
                                            "ray://host:port); only with kind: ray.")
    retries: int = Field(default=EXECUTOR_DEFAULTS["retries"], ge=0, le=MAX_RETRIES,
                         description="How often a failed unit runs again.")


class Experiment(ConfigModel):
    """One experiment: an env (a registered id with overrides), the seeds, and the kinds of
    policy to run on each seed. The keys its family checks (``policies``, ``adversaries``,
    ``planner_kwargs``, ``visibility``) are described here and checked by the family
    (`bounce_gym_experiments.families`)."""

    name: str = Field(description="Names the experiment's rows and plot files (one plain path "
                                  "component: no /, \\, control characters or leading '.', at "
                                  "most 100 bytes); also the default folder of its rl models.")
    env: str = Field(description="A registered environment id (docs: Environments).",
                     json_schema_extra={"enum": list(ENV_IDS)})
    env_kwargs: dict[str, Any] = Field(default_factory=dict, description=ENV_KWARGS_DESCRIPTION)
    seeds: list[int] | SeedRange = Field(
        default_factory=lambda: [EVALUATION_SEEDS_START],
        description=f"The evaluation seeds: a list of distinct integers, or {{start, count}}; "
                    f"each in [{EVALUATION_SEEDS_START}, 2**32 - 1] (disjoint from training's "
                    f"and tuning's), "
                    f"at most {MAX_SEEDS}. Every policy runs one episode per seed.")
    max_steps: int | None = Field(
        default=None, ge=1, le=MAX_STEPS,
        description="Longest episode in env steps. Default: the env's horizon, the one its "
                    "id registers or, for BounceNavigation-v1, derives from its map (what "
                    "training uses); another value needs horizon_reason.")
    horizon_reason: str | None = Field(
        default=None, description="Why max_steps differs from the registered horizon (only "
                                  "then).")
    policies: list[str] | None = Field(
        default=None,
        description="The kinds of policy to run, each once. Most families: planner (the "
                    "family's analytic planner), random (a random angle of Φ at every bump), "
                    "fixed (one policy per angle of Φ, and the best in hindsight), rl (the "
                    "trained models of rl_models). Default: every kind the family runs; some "
                    "families run other kinds (docs: Evaluation).")
    adversaries: list[str] | None = Field(
        default=None, description="The adversaries every policy meets, for the families that "
                                  "have them (the patrol game); each once.")
    visibility: dict[str, Any] | None = Field(
        default=None, description="Makes a single-robot experiment a safe-plan scenario: the "
                                  "scenario's options (docs: Evaluation).")
    planner_kwargs: dict[str, Any] | None = Field(
        default=None, description="Options of the family's planners, for the families that "
                                  "take them (e.g. {phi: 135}, which planners run: {models: "
                                  "[...]}, or where every policy of a monitoring experiment "
                                  "starts: {start: draw or cycle}; docs: Evaluation).")
    rl_models: str | list[str | ModelFolder] | None = Field(
        default=None,
        description="The folders of the models folder whose models rl runs (default: the "
                    "experiment's name): a name, or a list of names and {folder, env_kwargs}.")
    greedy: bool = Field(default=True, description="Also play every trained model's greedy "
                                                  "actions, rows named '(greedy)', beside its "
                                                  "sampled ones.")
    difficulty: Literal[DIFFICULTIES] | None = Field(  # type: ignore[valid-type]
        default=None, description="Labels the experiment in a leaderboard.")

    @field_validator("name")
    @classmethod
    def _name(cls, value: str, info: ValidationInfo) -> str:
        check_path_component(located(info), value, "a name for the plot files")
        return value

    @field_validator("env")
    @classmethod
    def _registered(cls, value: str, info: ValidationInfo) -> str:
        if value not in ENV_IDS:
            raise ConfigError(f"{located(info)}: unknown environment id {value!r}; registered: "
                              f"{list(ENV_IDS)}")
        return value

    @field_validator("env_kwargs")
    @classmethod
    def _no_horizon(cls, value: dict, info: ValidationInfo) -> dict:
        for key in _HORIZON_OPTIONS:
            if key in value:
                raise ConfigError(f"{located(info)}.{key}: not allowed; the experiment's "
                                  "horizon is max_steps (see horizon_reason)")
        return value

    @field_validator("seeds", mode="before")
    @classmethod
    def _seeds(cls, value: Any, info: ValidationInfo) -> Any:
        return evaluation_seeds(located(info), value)

    @field_validator("max_steps", mode="before")
    @classmethod
    def _steps(cls, value: Any, info: ValidationInfo) -> Any:
        if not isinstance(value, int):
            return value  # pydantic's type error
        return integer(located(info), value, 1, MAX_STEPS)

    @field_validator("policies", "adversaries")
    @classmethod
    def _listed_once(cls, value: list[str], info: ValidationInfo) -> list[str]:
        if len(set(value)) != len(value):
            what = "policy" if info.field_name == "policies" else "adversary"
            raise ConfigError(f"{located(info)}: each {what} once, got {value!r}")
        return value

    @field_validator("rl_models", mode="before")
    @classmethod
    def _folders(cls, value: Any, info: ValidationInfo) -> Any:
        return None if value is None else model_folders(located(info), value)

    @field_validator("difficulty", mode="before")
    @classmethod
    def _difficulty(cls, value: Any, info: ValidationInfo) -> Any:
        if value is not None and value not in DIFFICULTIES:
            raise ConfigError(f"{located(info)}: expected one of {DIFFICULTIES}, got {value!r}")
        return value

    @model_validator(mode="after")
    def _horizon(self, info: ValidationInfo) -> Experiment:
        self.max_steps = checked_horizon(where(info), self)
        return self


class EvaluationConfig(ConfigModel):
    """An evaluation configuration (``bounce-gym evaluate config.yaml``)."""

    name: str = Field(default="run", description="Names the run folder "
                                                 "<output>/<name>-<timestamp> (one plain path "
                                                 "component).")
    output: str = Field(default="runs", description="The folder the run folders go to.")
    models: str = Field(default="models", description="The folder of the trained models' "
                                                      "folders (rl_models).")
    experiments: list[Experiment] = Field(min_length=1, description="The experiments, each "
                                                                    "with its own name.")
    leaderboard: bool = Field(default=False, description="Also write leaderboard.md and "
                                                         "leaderboard.csv.")
    plots: bool = Field(default=True, description="Draw the figures into the run folder: each "
                                                  "experiment's trajectories, its family's "
                                                  "figures, the trained agents' profiles and "
                                                  "the leaderboard's.")
    executor: ExecutorSettings | None = Field(default=None, description="Where the units run "
                                                                        "(default: locally).")

    @field_validator("name")
    @classmethod
    def _name(cls, value: str, info: ValidationInfo) -> str:
        check_path_component(located(info), value, "a name for the run folder")
        return value

    @field_validator("output", "models")
    @classmethod
    def _path(cls, value: str, info: ValidationInfo) -> str:
        check_path_text(located(info), value)
        return models_folder(value) if info.field_name == "models" else value

    @field_validator("executor", mode="before")
    @classmethod
    def _executor(cls, value: Any, info: ValidationInfo) -> Any:
        if not isinstance(value, Mapping):
            return value  # pydantic's type error
        return executor_settings(value, located(info))

    @field_validator("experiments", mode="before")
    @classmethod
    def _experiments(cls, value: Any, info: ValidationInfo) -> Any:
        if not isinstance(value, list):
            return value  # pydantic's type error
        if not value:
            raise ConfigError(f"{located(info)}: expected at least one experiment")
        out, names = [], set()
        for k, item in enumerate(value):
            experiment = validate_experiment(item, f"{located(info)}[{k}]")
            if experiment.name in names:
                raise ConfigError(f"{located(info)}[{k}].name: {experiment.name!r} is used "
                                  "twice")
            names.add(experiment.name)
            out.append(experiment)
        return out  # checked models: pydantic takes them as they are (no second check)


def configs_folder() -> Path:
    """The shipped configurations: ``bounce_gym_experiments/configs`` when installed, else the checkout's
    top-level ``configs``."""
    here = Path(__file__).resolve().parent
    installed = here / "configs"
    return installed if installed.is_dir() else here.parent / "configs"


def training_configs_for(folder: str) -> list[str]:
    """The shipped training configurations (`configs_folder`) whose models go to the models'
    folder ``folder`` (their ``name``), as paths from the current folder where they lie below it."""
    found = []
    for path in sorted(configs_folder().glob("train_*.yaml")):
        document = read_document(path, "config")
        if isinstance(document, dict) and document.get("name") == folder:
            found.append(_shown(path))
    return found


def _shown(path: Path) -> str:
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def load_config(path: str | Path | None = None) -> dict:
    """The YAML configuration at ``path`` (the default configuration if ``None``), read within
    the limits of `bounce_gym.documents` (4 MiB, nesting 32 deep, 120,000 nodes with aliases
    expanded) but otherwise unvalidated; relative map files in ``env_kwargs.world`` resolved
    against the file's folder."""
    file = configs_folder() / DEFAULT_CONFIG_NAME if path is None else Path(path)
    config = read_document(file, "config")
    _resolve_map_files(config, file.parent)
    return config


def _resolve_map_files(config: object, folder: Path) -> None:
    experiments = config.get("experiments") if isinstance(config, dict) else None
    for exp in experiments if isinstance(experiments, list) else []:
        kwargs = exp.get("env_kwargs") if isinstance(exp, dict) else None
        if not isinstance(kwargs, dict):
            continue
        world, flow = kwargs.get("world"), kwargs.get("flow")
        if isinstance(world, str) and world.endswith(_MAP_SUFFIXES) \
                and not Path(world).is_absolute():
            kwargs["world"] = str(folder / world)
        if isinstance(flow, str) and Path(flow).suffix and not Path(flow).is_absolute():
            kwargs["flow"] = str(folder / flow)


def validate_config(config: object) -> dict:
    """Check a configuration (`EvaluationConfig`) and fill in the defaults; raise `ConfigError`
    naming the key and what is allowed. A validated configuration validates to itself."""
    checked = EvaluationConfig.check(config, "config")
    out = checked.model_dump(exclude_none=True)
    if checked.executor is not None:  # every key, unset ones as None (the run's provenance)
        out["executor"] = checked.executor.model_dump()
    return out


def validate_experiment(item: object, at: str) -> Experiment:
    """One experiment (`Experiment`) checked, then by its family (`Family.validate`, which also
    fills in the family's defaults), with its ``rl_models`` (default: the folder of its name)
    when anything of it is ``rl``, and checked again with what the family filled in; ``at``
    locates it in errors."""
    experiment = Experiment.check(item, at).model_dump(exclude_none=True)
    from bounce_gym_experiments.registry import family_of  # the families import this module

    family = family_of(experiment, at)
    try:
        family.validate(experiment)
    except ConfigError as exc:
        raise ConfigError(f"{at}.{exc}") from None
    plays_rl = "rl" in experiment["policies"] or "rl" in experiment.get("adversaries", ())
    if plays_rl and "rl_models" not in experiment:
        experiment["rl_models"] = model_folders(
            f"{at}.name (the folder of its rl models)", experiment["name"])
    return Experiment.check(experiment, at)


def registered_horizon(env_id: str) -> int | None:
    """The episode limit an env id registers: Gymnasium's ``max_episode_steps`` or PettingZoo's
    ``max_cycles`` (``None`` if it registers none)."""
    if is_pettingzoo_id(env_id):
        return pettingzoo.parallel_registry[env_id].max_cycles
    return gym.spec(env_id).max_episode_steps


def registered_kwargs(env_id: str) -> dict:
    """The keyword arguments an env id registers (Gymnasium or PettingZoo)."""
    spec = (pettingzoo.parallel_registry[env_id] if is_pettingzoo_id(env_id)
            else gym.spec(env_id))
    return dict(spec.kwargs or {})


def evaluation_seeds(where: str, seeds: object) -> list[int]:
    """The evaluation seeds of ``seeds`` (a list, or ``{start, count}``), all held out, at most
    `MAX_SEEDS` of them, each at most `MAX_SEED`; checked in time linear in their number."""
    if isinstance(seeds, Mapping):
        checked = SeedRange.check(seeds, where)
        return list(range(checked.start, checked.start + checked.count))
    if not isinstance(seeds, list):
        raise ConfigError(f"{where}: expected list or dict, got {type(seeds).__name__}")
    if not seeds or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds):
        raise ConfigError(f"{where}: expected a non-empty list of integers or {{start, count}}, "
                          f"got {shorten(seeds)}")
    if len(seeds) > MAX_SEEDS:
        raise ConfigError(f"{where}: at most {MAX_SEEDS} seeds, got {len(seeds)}")
    reasons = [reserved_overlap(range(s, s + 1)) for s in seeds]
    first = next((reason for reason in reasons if reason is not None), None)
    if first is not None:
        clash = [s for s, reason in zip(seeds, reasons, strict=True) if reason == first]
        raise ConfigError(f"{where}: evaluation seeds must not overlap {first} (baselines.seeds), "
                          f"got {clash[:5]}{' ...' if len(clash) > 5 else ''}")
    low = [s for s in seeds if s < EVALUATION_SEEDS_START]
    if low:
        raise ConfigError(f"{where}: evaluation seeds must be >= {EVALUATION_SEEDS_START} "
                          f"(baselines.seeds), got {low[:5]}{' ...' if len(low) > 5 else ''}")
    high = [s for s in seeds if s > MAX_SEED]
    if high:
        raise ConfigError(f"{where}: evaluation seeds must be <= {MAX_SEED}, got {high[:5]}"
                          f"{' ...' if len(high) > 5 else ''}")
    twice = sorted(s for s, n in Counter(seeds).items() if n > 1)
    if twice:
        raise ConfigError(f"{where}: every seed once (an episode counts once), repeated: "
                          f"{twice[:5]}{' ...' if len(twice) > 5 else ''}")
    return list(seeds)


def env_horizon(env_id: str, env_kwargs: Mapping[str, Any]) -> int | None:
    """The horizon of ``env_id`` made with ``env_kwargs``: the registered one
    (`registered_horizon`), or for an id of `MAP_HORIZON` the one its env derives from its map
    (what ``gym.make`` reports as ``env.spec.max_episode_steps``). The env is built (and closed)
    either way, so bad ``env_kwargs`` raise here, as the env would raise them."""
    if is_pettingzoo_id(env_id):
        env = pettingzoo.make("parallel", env_id, **env_kwargs)
    else:
        env = gym.make(env_id, **env_kwargs)
    try:
        if env_id not in MAP_HORIZON:
            return registered_horizon(env_id)
        return env.spec.max_episode_steps if env.spec is not None else None
    finally:
        env.close()


def checked_horizon(where: str, exp: Experiment) -> int:
    """The experiment's ``max_steps``: the env's horizon (`env_horizon`), or another with its
    reason."""
    with config_errors(f"{where}.env_kwargs"):
        horizon = env_horizon(exp.env, exp.env_kwargs)
    reason = exp.horizon_reason
    if reason is not None and not reason.strip():
        raise ConfigError(f"{where}.horizon_reason: expected a non-empty explanation")
    if exp.max_steps is None:
        if horizon is None:
            raise ConfigError(f"{where}.max_steps: {exp.env} registers no horizon; give "
                              "max_steps and horizon_reason")
        if reason is not None:
            raise ConfigError(f"{where}.horizon_reason: only with a max_steps that differs from "
                              f"the registered horizon {horizon}")
        return horizon
    if exp.max_steps == horizon and reason is not None:
        raise ConfigError(f"{where}.horizon_reason: only with a max_steps that differs from "
                          f"the registered horizon {horizon}")
    if exp.max_steps != horizon and reason is None:
        source = "derives on this map" if exp.env in MAP_HORIZON else "registers"
        raise ConfigError(f"{where}.max_steps: {exp.max_steps} differs from the horizon {horizon} "
                          f"that {exp.env} {source} (and training uses); leave max_steps out, "
                          "or say why in horizon_reason")
    return exp.max_steps


def model_folders(field: str, entries: object) -> list[dict]:
    """``rl_models`` as a list of ``{folder, env_kwargs}``."""
    if not isinstance(entries, str | list):
        raise ConfigError(f"{field}: expected str or list, got {type(entries).__name__}")
    listed = isinstance(entries, list)
    entries = entries if listed else [entries]
    if not entries:
        raise ConfigError(f"{field}: expected a folder name or a non-empty list of them")
    out = []
    for i, entry in enumerate(entries):
        at = f"{field}[{i}]" if listed else field
        if isinstance(entry, str):
            check_folder_name(at, entry)
            entry = {"folder": entry}
        if not isinstance(entry, Mapping):
            raise ConfigError(f"{at}: expected a folder name or {{folder, env_kwargs}}, got "
                              f"{entry!r}")
        out.append(ModelFolder.check(entry, at).model_dump())
    folders = [e["folder"] for e in out]
    if len(set(folders)) != len(folders):
        raise ConfigError(f"{field}: a folder is named twice: {folders}")
    return out
