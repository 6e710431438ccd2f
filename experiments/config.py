"""Evaluation configurations: loading YAML, the default configuration, and validation.

A configuration lists *experiments*; each names a registered environment id — a Gymnasium id
(``bounce_gym/BounceNavigation-v0``, …) or a multi-robot PettingZoo id
(``bounce_gym/MultiBounceCoverage-v0``, …) — with overrides, the seeds, and which policies to
run:

* ``planner`` — the analytic planner of the experiment's family (`experiments.registry`);
* ``random`` — a random angle of Φ at every bump (every robot its own);
* ``fixed`` — one policy per angle of Φ (the papers' single bounce policies; all robots alike);
* ``rl`` — every Stable-Baselines3 model found under ``models/<experiment name>/`` (what
  ``bounce-gym train`` saves there); for several robots one PPO model shared by all of them.

Optional keys: ``rl_models`` names the sub-folder of ``models/`` to load instead of the
experiment name, so several experiments can score one trained model; ``visibility`` makes a
single-robot experiment a safe-plan scenario (`experiments.families.visibility`);
``planner_kwargs`` (multi-robot only) are keyword arguments of the planner's ``for_env`` (e.g.
``{phi: 135}``). A multi-robot env is built with ``max_cycles = max_steps``, so ``env_kwargs``
may not set ``max_cycles``.

The default configuration is the packaged ``eval_default.yaml`` (the top-level ``configs/``
folder of a source checkout, ``experiments/configs/`` once installed).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path

import gymnasium as gym
import yaml

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.rl.model_files import check_folder_name
from bounce_gym.envs.registration import PETTINGZOO_ENVS, is_pettingzoo_id
from bounce_gym.errors import ConfigError

POLICY_KINDS = ("planner", "random", "fixed", "rl")
DEFAULT_CONFIG_NAME = "eval_default.yaml"

_TOP_KEYS = {"name": str, "output": str, "models": str, "experiments": list}
_EXPERIMENT_KEYS = {"name": str, "env": str, "env_kwargs": dict, "seeds": list,
                    "max_steps": int, "policies": list, "visibility": dict,
                    "planner_kwargs": dict, "rl_models": str}


def configs_folder() -> Path:
    """The shipped configurations: ``experiments/configs`` when installed, else the checkout's
    top-level ``configs``."""
    here = Path(__file__).resolve().parent
    installed = here / "configs"
    return installed if installed.is_dir() else here.parent / "configs"


def load_config(path: str | Path | None = None) -> dict:
    """The YAML configuration at ``path`` (the default configuration if ``None``), unvalidated."""
    file = configs_folder() / DEFAULT_CONFIG_NAME if path is None else Path(path)
    if not file.is_file():
        raise ConfigError(f"config: file {str(path if path is not None else file)!r} does not "
                          "exist")
    try:
        return yaml.safe_load(file.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:  # one line: what is wrong and where
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"config: {file} is not valid YAML: {problem}{at}") from None


def validate_config(config: object) -> dict:
    """Check a configuration and fill in the defaults; raise `ConfigError` naming the key and
    what is allowed."""
    if not isinstance(config, Mapping):
        raise ConfigError(f"config: expected a mapping, got {type(config).__name__}")
    _check_keys("config", config, _TOP_KEYS, required=("experiments",))
    config = copy.deepcopy(dict(config))
    config.setdefault("name", "run")
    config.setdefault("output", "runs")
    config.setdefault("models", "models")
    if not config["experiments"]:
        raise ConfigError("config.experiments: expected at least one experiment")
    names = set()
    for k, exp in enumerate(config["experiments"]):
        where = f"config.experiments[{k}]"
        if not isinstance(exp, Mapping):
            raise ConfigError(f"{where}: expected a mapping, got {type(exp).__name__}")
        _check_keys(where, exp, _EXPERIMENT_KEYS, required=("name", "env"))
        exp.setdefault("env_kwargs", {})
        exp.setdefault("seeds", [0])
        exp.setdefault("max_steps", 200)
        exp.setdefault("policies", list(POLICY_KINDS))
        if exp["name"] in names:
            raise ConfigError(f"{where}.name: {exp['name']!r} is used twice")
        names.add(exp["name"])
        if is_pettingzoo_id(exp["env"]):
            _check_multi_robot(where, exp)
        elif exp["env"] not in gym.registry:
            known = sorted(i for i in gym.registry if i.startswith("bounce_gym/"))
            raise ConfigError(f"{where}.env: unknown environment id {exp['env']!r}; registered: "
                              f"{known + list(PETTINGZOO_ENVS)}")
        elif "planner_kwargs" in exp:
            raise ConfigError(f"{where}.planner_kwargs: only for multi-robot experiments "
                              f"(env one of {list(PETTINGZOO_ENVS)})")
        if "rl_models" in exp:
            check_folder_name(f"{where}.rl_models", exp["rl_models"])
        elif "rl" in exp["policies"]:
            check_folder_name(f"{where}.name (the folder of its rl models)", exp["name"])
        if not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0
                   for s in exp["seeds"]):
            raise ConfigError(f"{where}.seeds: expected a list of integers >= 0, got "
                              f"{exp['seeds']!r}")
        if exp["max_steps"] < 1:
            raise ConfigError(f"{where}.max_steps: expected an integer >= 1")
        unknown = [p for p in exp["policies"] if p not in POLICY_KINDS]
        if unknown:
            raise ConfigError(f"{where}.policies: unknown {unknown}; allowed are {POLICY_KINDS}")
    return config


def _check_multi_robot(where: str, exp: dict) -> None:
    if "visibility" in exp:
        raise ConfigError(f"{where}.visibility: only for single-robot experiments")
    if "max_cycles" in exp["env_kwargs"]:
        raise ConfigError(f"{where}.env_kwargs.max_cycles: not allowed; the experiment's "
                          "max_steps is the env's max_cycles")
    exp.setdefault("planner_kwargs", {})


def _check_keys(where: str, mapping: Mapping, allowed: dict, required: tuple) -> None:
    unknown = sorted(set(mapping) - set(allowed))
    if unknown:
        raise ConfigError(f"{where}: unknown keys {unknown}; allowed are {sorted(allowed)}")
    for key in required:
        if key not in mapping:
            raise ConfigError(f"{where}: missing key {key!r}")
    for key, kind in allowed.items():
        if key in mapping and not isinstance(mapping[key], kind):
            raise ConfigError(f"{where}.{key}: expected {kind.__name__}, got "
                              f"{type(mapping[key]).__name__}")
