"""Evaluation configurations: loading YAML, the default configuration, and validation.

A configuration lists *experiments*; each names a registered environment id — a Gymnasium id
(``bounce_gym/BounceNavigation-v0``, ``bounce_gym/Drifter-v0``, …) or a multi-robot PettingZoo
id (``bounce_gym/MultiBounceCoverage-v0``, ``bounce_gym/MultiDrifter-v0``, …) — with
overrides, the seeds, and which policies to run:

* ``planner`` — the analytic planner of the experiment's family (`bounce_gym_experiments.registry`);
* ``random`` — a random angle of Φ at every bump (every robot its own), drawn from the
  episode's seed;
* ``fixed`` — one policy per angle of Φ (the papers' single bounce policies; all robots alike);
  with two or more of them the report adds the best fixed angle per episode in hindsight
  (`bounce_gym_experiments.oracle`);
* ``rl`` — every Stable-Baselines3 model ``<algo>_seed<N>.zip`` found in the experiment's model
  folders (what ``bounce-gym train`` saves); for several robots one PPO model shared by all.

The drifter families read the kinds their own way (`bounce_gym_experiments.families.drifters`): a random
legal layer move per step for ``random`` and always drift for ``fixed``; the deployment family
runs ``planner`` (Alg. 5.2 and the greedy deployment) and ``random`` (random cells). A kind a
family does not run is an error naming ``policies``.

The patrol experiments (``bounce_gym/Patrol-v0``, `bounce_gym_experiments.families.patrolling`) have
patrollers and an adversary: ``policies`` are the patrollers' kinds, ``planner`` (MAECT and the
Stackelberg equilibrium mixture), ``random`` (the uniform random walk), ``perimeter`` (the
perimeter patrols after Agmon et al.) and ``rl`` (default: all four); ``adversaries`` are
``best_response`` (told the strategy), ``best_response_positions`` (told the positions too) and
``rl`` (default: the two best responses). Every patroller meets every adversary. No other
experiment takes ``adversaries``.

**Seeds.** Evaluation seeds are disjoint from training seeds (`baselines.seeds`): every seed
must be at least ``EVALUATION_SEEDS_START`` (10,000) and at most ``MAX_SEED`` (2**32 - 1).
``seeds`` is a list of distinct integers or ``{start: 10000, count: 200}`` (the seeds start,
start + 1, …), at most ``MAX_SEEDS`` (100,000) seeds either way; the validated configuration
holds the list. Default: one seed, 10,000.

**Horizon.** An episode lasts at most the horizon its env registers — Gymnasium's
``max_episode_steps``, PettingZoo's ``max_cycles`` — which is also what training uses.
``max_steps`` may be left out (the validated configuration holds the registered horizon) or
restate it; a different ``max_steps`` (at most ``MAX_STEPS``, 10**6) needs
``horizon_reason: <why>`` in the same experiment, and then sets the env's own limit
(``gym.make(max_episode_steps=...)``, ``max_cycles``), so that the env and the episode loop stop
together. ``env_kwargs`` may set neither limit.

``name`` (default ``run``) names the run folder and every experiment's ``name`` its plot files:
each is one plain path component (`bounce_gym.files.check_path_component`: no ``/``, ``\\``,
control characters or leading ``.``, at most 100 bytes).

Optional keys: ``rl_models`` — the folder of ``models/`` to load instead of the experiment name,
or a list of them; an entry may be ``{folder: <name>, env_kwargs: {privileged: true}}`` to run
models trained with another observation (only ``privileged`` and ``history`` may differ, so the
episodes stay the same); ``visibility`` makes a single-robot experiment a safe-plan scenario
(`bounce_gym_experiments.families.visibility`); ``planner_kwargs`` are keyword arguments
of the planner's ``for_env`` (e.g. ``{phi: 135}``), and for ``bounce_gym/Drifter-v0`` and the
navigation experiments the planners to run and their options
(`bounce_gym_experiments.families.drifters.drifter_planners`, `bounce_gym_experiments.families.navigation.navigation_planners`); ``difficulty`` (``easy``, ``medium`` or
``hard``) labels the experiment in a leaderboard. A top-level ``leaderboard: true`` makes the
evaluation write ``leaderboard.md`` and ``leaderboard.csv`` (`bounce_gym_experiments.leaderboard`). A
top-level ``executor: {kind: local|ray, workers: N, address: ..., retries: 2}`` says where the
evaluation's units run (`bounce_gym_experiments.executors.executor_settings`; the flags ``--executor``,
``--workers`` and ``--address`` override it); it does not change the results.

A relative map file in ``env_kwargs.world`` (``*.yaml``, ``*.yml``, ``*.json``) or flow file
in ``env_kwargs.flow`` (a path with a suffix, e.g. ``*.nc``; zoo names have none) of a
configuration file is read relative to that file's folder.

The default configuration is the packaged ``eval_default.yaml`` (the top-level ``configs/``
folder of a source checkout, ``bounce_gym_experiments/configs/`` once installed).
"""

from __future__ import annotations

import copy
from collections import Counter
from collections.abc import Mapping
from pathlib import Path

import gymnasium as gym
import pettingzoo

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.rl.model_files import check_folder_name
from baselines.seeds import EVALUATION_SEEDS_START
from bounce_gym.documents import read_document
from bounce_gym.envs.registration import (
    DRIFTER_PETTINGZOO_ENVS,
    GYM_ENVS,
    GYMNASIUM_IDS,
    PETTINGZOO_ENVS,
    is_drifter_id,
    is_pettingzoo_id,
)
from bounce_gym.errors import ConfigError
from bounce_gym.files import check_path_component, check_path_text
from bounce_gym.validate import integer, unknown_keys
from bounce_gym_experiments.executors import executor_settings

POLICY_KINDS = ("planner", "random", "fixed", "rl")
#: the env of the patrol experiments (`bounce_gym_experiments.families.patrolling`)
PATROL_ENV = "bounce_gym/Patrol-v0"
#: the patrollers' policy kinds of a patrol experiment
PATROL_POLICY_KINDS = ("planner", "random", "perimeter", "rl")
#: the adversaries of a patrol experiment: the Stackelberg best response told the strategy, or
#: also the patrollers' positions, and trained models
ADVERSARY_KINDS = ("best_response", "best_response_positions", "rl")
DIFFICULTIES = ("easy", "medium", "hard")
DEFAULT_CONFIG_NAME = "eval_default.yaml"
#: Most evaluation seeds of one experiment (episodes per policy), and the largest seed.
MAX_SEEDS = 100_000
MAX_SEED = 2**32 - 1
#: Longest episode an experiment's ``max_steps`` may ask for.
MAX_STEPS = 10**6
#: env options a model folder of ``rl_models`` may set differently (observation only)
OBSERVATION_OPTIONS = frozenset({"privileged", "history"})
_MAP_SUFFIXES = (".yaml", ".yml", ".json")
#: the PettingZoo ids (several robots or drifters)
_PARALLEL_IDS = [*PETTINGZOO_ENVS, *DRIFTER_PETTINGZOO_ENVS]

#: the single-robot tasks whose experiments take ``planner_kwargs`` (the navigation planners)
NAVIGATION_TASKS = ("navigation", "goal_navigation")
_TOP_KEYS = {"name": str, "output": str, "models": str, "experiments": list, "leaderboard": bool,
             "executor": dict}
_EXPERIMENT_KEYS = {"name": str, "env": str, "env_kwargs": dict, "seeds": list | dict,
                    "max_steps": int, "horizon_reason": str, "policies": list,
                    "visibility": dict, "planner_kwargs": dict, "rl_models": str | list,
                    "difficulty": str, "adversaries": list}


def configs_folder() -> Path:
    """The shipped configurations: ``bounce_gym_experiments/configs`` when installed, else the checkout's
    top-level ``configs``."""
    here = Path(__file__).resolve().parent
    installed = here / "configs"
    return installed if installed.is_dir() else here.parent / "configs"


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
    """Check a configuration and fill in the defaults; raise `ConfigError` naming the key and
    what is allowed. A validated configuration validates to itself."""
    if not isinstance(config, Mapping):
        raise ConfigError(f"config: expected a mapping, got {type(config).__name__}")
    _check_keys("config", config, _TOP_KEYS, required=("experiments",))
    config = copy.deepcopy(dict(config))
    config.setdefault("name", "run")
    config.setdefault("output", "runs")
    config.setdefault("models", "models")
    config.setdefault("leaderboard", False)
    check_path_component("config.name", config["name"], "a name for the run folder")
    for key in ("output", "models"):
        check_path_text(f"config.{key}", config[key])
    if "executor" in config:
        config["executor"] = executor_settings(config["executor"], "config.executor")
    if not config["experiments"]:
        raise ConfigError("config.experiments: expected at least one experiment")
    names = set()
    for k, exp in enumerate(config["experiments"]):
        where = f"config.experiments[{k}]"
        if not isinstance(exp, Mapping):
            raise ConfigError(f"{where}: expected a mapping, got {type(exp).__name__}")
        _check_keys(where, exp, _EXPERIMENT_KEYS, required=("name", "env"))
        check_path_component(f"{where}.name", exp["name"], "a name for the plot files")
        exp.setdefault("env_kwargs", {})
        patrol = exp["env"] == PATROL_ENV
        exp.setdefault("policies", list(PATROL_POLICY_KINDS if patrol else POLICY_KINDS))
        if exp["name"] in names:
            raise ConfigError(f"{where}.name: {exp['name']!r} is used twice")
        names.add(exp["name"])
        if is_pettingzoo_id(exp["env"]):
            _check_multi_robot(where, exp)
        elif exp["env"] not in GYMNASIUM_IDS:
            raise ConfigError(f"{where}.env: unknown environment id {exp['env']!r}; registered: "
                              f"{[*GYMNASIUM_IDS, *_PARALLEL_IDS]}")
        elif "planner_kwargs" in exp and not (is_drifter_id(exp["env"])
                                              or _task(exp) in NAVIGATION_TASKS):
            raise ConfigError(f"{where}.planner_kwargs: only for multi-robot experiments "
                              f"(env one of {_PARALLEL_IDS}), bounce_gym/Drifter-v0 and "
                              f"navigation (task one of {list(NAVIGATION_TASKS)})")
        if "max_episode_steps" in exp["env_kwargs"]:
            raise ConfigError(f"{where}.env_kwargs.max_episode_steps: not allowed; the "
                              "experiment's horizon is max_steps (see horizon_reason)")
        exp["seeds"] = _seeds(f"{where}.seeds", exp.get("seeds", [EVALUATION_SEEDS_START]))
        _check_horizon(where, exp)
        kinds = PATROL_POLICY_KINDS if patrol else POLICY_KINDS
        unknown = [p for p in exp["policies"] if p not in kinds]
        if unknown:
            raise ConfigError(f"{where}.policies: unknown {unknown}; allowed are {kinds}")
        if not exp["policies"]:
            raise ConfigError(f"{where}.policies: expected a non-empty list of {kinds}")
        if len(set(exp["policies"])) != len(exp["policies"]):
            raise ConfigError(f"{where}.policies: each policy once, got {exp['policies']}")
        _check_adversaries(where, exp, patrol)
        if "rl_models" in exp or "rl" in exp["policies"] or "rl" in exp.get("adversaries", []):
            exp["rl_models"] = _model_folders(where, exp)
        if "difficulty" in exp and exp["difficulty"] not in DIFFICULTIES:
            raise ConfigError(f"{where}.difficulty: expected one of {DIFFICULTIES}, got "
                              f"{exp['difficulty']!r}")
    return config


def registered_horizon(env_id: str) -> int | None:
    """The episode limit an env id registers: Gymnasium's ``max_episode_steps`` or PettingZoo's
    ``max_cycles`` (``None`` if it registers none)."""
    if is_pettingzoo_id(env_id):
        return pettingzoo.parallel_registry[env_id].max_cycles
    return gym.spec(env_id).max_episode_steps


def world_name(experiment: Mapping) -> str:
    """The world an experiment runs on: its ``env_kwargs.world`` (a map file by its file name)
    or the one its env id registers; for a drifter env the flow (``env_kwargs.flow``: a zoo
    name, a NetCDF file by its file name or a field by its name; else the env's default)."""
    if is_drifter_id(experiment["env"]):
        from bounce_gym.envs.drifters.options import DrifterOptions  # only if needed

        world = experiment["env_kwargs"].get("flow", DrifterOptions.model_fields["flow"].default)
        return Path(world).name if isinstance(world, str) else getattr(world, "name", "?")
    world = experiment["env_kwargs"].get("world")
    if world is None:
        spec = (pettingzoo.parallel_registry[experiment["env"]]
                if is_pettingzoo_id(experiment["env"]) else gym.spec(experiment["env"]))
        world = spec.kwargs.get("world", "?")
    return Path(world).name if isinstance(world, str) else getattr(world, "name", str(world))


def _task(experiment: Mapping) -> object:
    """The task of a single-robot bouncing experiment: its ``env_kwargs.task`` or the one its
    env id registers."""
    return experiment["env_kwargs"].get("task", GYM_ENVS.get(experiment["env"], ({}, 0))[0]
                                        .get("task"))


def _seeds(where: str, seeds: object) -> list[int]:
    """The evaluation seeds of ``seeds`` (a list, or ``{start, count}``), all held out, at most
    `MAX_SEEDS` of them, each at most `MAX_SEED`; checked in time linear in their number."""
    if isinstance(seeds, Mapping):
        _check_keys(where, seeds, {"start": int, "count": int}, required=("start", "count"))
        start = integer(f"{where}.start", seeds["start"], minimum=EVALUATION_SEEDS_START,
                        maximum=MAX_SEED)
        count = integer(f"{where}.count", seeds["count"], minimum=1,
                        maximum=min(MAX_SEEDS, MAX_SEED - start + 1))
        return list(range(start, start + count))
    if not seeds or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds):
        raise ConfigError(f"{where}: expected a non-empty list of integers or {{start, count}}, "
                          f"got {_shorten(seeds)}")
    if len(seeds) > MAX_SEEDS:
        raise ConfigError(f"{where}: at most {MAX_SEEDS} seeds, got {len(seeds)}")
    low = [s for s in seeds if s < EVALUATION_SEEDS_START]
    if low:
        raise ConfigError(f"{where}: evaluation seeds must be >= {EVALUATION_SEEDS_START} "
                          f"(training uses the seeds below it, baselines.seeds), got {low[:5]}"
                          f"{' ...' if len(low) > 5 else ''}")
    high = [s for s in seeds if s > MAX_SEED]
    if high:
        raise ConfigError(f"{where}: evaluation seeds must be <= {MAX_SEED}, got {high[:5]}"
                          f"{' ...' if len(high) > 5 else ''}")
    twice = sorted(s for s, n in Counter(seeds).items() if n > 1)
    if twice:
        raise ConfigError(f"{where}: every seed once (an episode counts once), repeated: "
                          f"{twice[:5]}{' ...' if len(twice) > 5 else ''}")
    return list(seeds)


def _shorten(value: object) -> str:
    """``repr(value)``, cut to 80 characters (a list of a million seeds is not repeated)."""
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:77]}..."


def _check_horizon(where: str, exp: dict) -> None:
    horizon = registered_horizon(exp["env"])
    reason = exp.get("horizon_reason")
    if reason is not None and not reason.strip():
        raise ConfigError(f"{where}.horizon_reason: expected a non-empty explanation")
    if "max_steps" not in exp:
        if horizon is None:
            raise ConfigError(f"{where}.max_steps: {exp['env']} registers no horizon; give "
                              "max_steps and horizon_reason")
        if reason is not None:
            raise ConfigError(f"{where}.horizon_reason: only with a max_steps that differs from "
                              f"the registered horizon {horizon}")
        exp["max_steps"] = horizon
        return
    steps = integer(f"{where}.max_steps", exp["max_steps"], minimum=1, maximum=MAX_STEPS)
    if steps == horizon and reason is not None:
        raise ConfigError(f"{where}.horizon_reason: only with a max_steps that differs from "
                          f"the registered horizon {horizon}")
    if steps != horizon and reason is None:
        raise ConfigError(f"{where}.max_steps: {steps} differs from the horizon {horizon} that "
                          f"{exp['env']} registers (and training uses); leave max_steps out, or "
                          "say why in horizon_reason")


def _model_folders(where: str, exp: dict) -> list[dict]:
    """``rl_models`` as a list of ``{folder, env_kwargs}`` (default: the experiment's name)."""
    given = "rl_models" in exp
    field = f"{where}.rl_models" if given else f"{where}.name (the folder of its rl models)"
    entries = exp.get("rl_models", exp["name"])
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
        _check_keys(at, entry, {"folder": str, "env_kwargs": dict}, required=("folder",))
        check_folder_name(f"{at}.folder", entry["folder"])
        extra = dict(entry.get("env_kwargs", {}))
        if set(extra) - OBSERVATION_OPTIONS:
            raise ConfigError(f"{at}.env_kwargs: only observation options "
                              f"{sorted(OBSERVATION_OPTIONS)} may differ from the experiment's, "
                              f"got {sorted(set(extra) - OBSERVATION_OPTIONS)}")
        out.append({"folder": entry["folder"], "env_kwargs": extra})
    folders = [e["folder"] for e in out]
    if len(set(folders)) != len(folders):
        raise ConfigError(f"{field}: a folder is named twice: {folders}")
    return out


def _check_adversaries(where: str, exp: dict, patrol: bool) -> None:
    """A patrol experiment's ``adversaries`` (default: both best responses); no other
    experiment has adversaries."""
    if not patrol:
        if "adversaries" in exp:
            raise ConfigError(f"{where}.adversaries: only for {PATROL_ENV} experiments")
        return
    exp.setdefault("adversaries", list(ADVERSARY_KINDS[:2]))
    unknown = [a for a in exp["adversaries"] if a not in ADVERSARY_KINDS]
    if unknown or not exp["adversaries"]:
        raise ConfigError(f"{where}.adversaries: expected a non-empty list of {ADVERSARY_KINDS}, "
                          f"got {exp['adversaries']!r}")
    if len(set(exp["adversaries"])) != len(exp["adversaries"]):
        raise ConfigError(f"{where}.adversaries: each adversary once, got {exp['adversaries']!r}")


def _check_multi_robot(where: str, exp: dict) -> None:
    if "visibility" in exp:
        raise ConfigError(f"{where}.visibility: only for single-robot experiments")
    if "max_cycles" in exp["env_kwargs"]:
        raise ConfigError(f"{where}.env_kwargs.max_cycles: not allowed; the experiment's "
                          "horizon is max_steps (see horizon_reason)")
    exp.setdefault("planner_kwargs", {})


def _check_keys(where: str, mapping: Mapping, allowed: dict, required: tuple) -> None:
    unknown_keys(where, mapping, allowed)
    for key in required:
        if key not in mapping:
            raise ConfigError(f"{where}: missing key {key!r}")
    for key, kind in allowed.items():
        if key in mapping and not isinstance(mapping[key], kind):
            raise ConfigError(f"{where}.{key}: expected {_kind_name(kind)}, got "
                              f"{type(mapping[key]).__name__}")


def _kind_name(kind) -> str:
    return " or ".join(k.__name__ for k in getattr(kind, "__args__", (kind,)))
