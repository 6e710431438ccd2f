"""Policy evaluation: every applicable policy on the same worlds, tasks, backends and seeds.

A configuration (YAML file or the built-in `DEFAULT_CONFIG`) lists *experiments*; each names a
registered environment id (or ``bounce_gym/Bounce-v0``) with overrides, the seeds, and which
policies to run:

* ``planner`` — the task's analytic reference policy (navigation: the roadmap plan executor;
  coverage: the optimal policy mixture α; localization: the angle-switching planner; an
  experiment with a ``visibility`` block: the safe plan of Nilles et al., see
  `baselines.visibility.scenario`);
* ``random`` — a random angle from Φ at every bump;
* ``fixed`` — one policy per angle of Φ (the papers' single bounce policies);
* ``rl`` — every Stable-Baselines3 model found under ``models/<experiment name>/`` (what
  ``train.py`` saves there).

``rl_models`` (optional) names the sub-folder of ``models/`` to load instead of the experiment
name, so several experiments can score one trained model.

An experiment whose ``env`` is a multi-robot PettingZoo id (``bounce_gym/MultiBounce*-v0``) runs
through `experiments.multi_evaluation` — the planners of Alam & Bobadilla, random bouncing, fixed
angles and one shared PPO policy, with steps to full coverage or monitoring metrics; it may set
``planner_kwargs`` (see that module).

Results are one row per (experiment, policy, seed): return, steps, ticks and the task's metrics
(success and ticks to goal vs the planner's predicted cost; coverage fraction and distance to the
target; final localization candidates). `run` returns them; `summarise` gives mean and standard
deviation per (experiment, policy); `evaluate.py` prints the tables and writes CSV, JSON and
plots into a run folder.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.policy import FixedAnglePolicy, Policy, RandomAnglePolicy
from bounce_gym.errors import ConfigError
from experiments.multi_evaluation import (
    MULTI_ENV_IDS,
    is_multi,
    run_multi_experiment,
    validate_multi_experiment,
)

POLICY_KINDS = ("planner", "random", "fixed", "rl")

DEFAULT_CONFIG: dict = {
    "name": "default",
    "output": "runs",
    "models": "models",
    "experiments": [
        {
            "name": "navigation-lab",
            "env": "bounce_gym/BounceNavigation-v0",
            "env_kwargs": {"backend": "cell", "angles": [45, 90, 135],
                           "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}},
            "seeds": list(range(20)),
            "max_steps": 100,
            "policies": ["planner", "random", "fixed", "rl"],
        },
        {
            "name": "coverage-lab",
            "env": "bounce_gym/BounceCoverage-v0",
            "env_kwargs": {"world": "lab_fig1", "backend": "cell", "cell_bins": 360,
                           "angles": [30, 75, 315],
                           "noise": {"type": "reliable", "r": 0.8, "eps_deg": 5}},
            "seeds": [0, 1, 2],
            "max_steps": 1500,
            "policies": ["planner", "random", "fixed"],
        },
        {
            "name": "visibility-two-rooms",
            "env": "bounce_gym/Bounce-v0",
            "env_kwargs": {"world": "two_rooms", "bounce_rule": "fixed",
                           "action_type": "continuous", "angle_range": [0.5, 179.5]},
            "visibility": {"start": 0, "goal": 16, "plan": "fewest"},
            "seeds": list(range(20)),
            "max_steps": 10,
            "policies": ["planner", "random", "rl"],
        },
        {
            "name": "visibility-patrol-heptagon",
            "env": "bounce_gym/Bounce-v0",
            "env_kwargs": {"world": "heptagon", "bounce_rule": "fixed",
                           "action_type": "continuous", "angle_range": [0.5, 179.5]},
            "visibility": {"start": 0, "patrol": [0, 1, 2, 3, 4, 5, 6], "theta": 0.1},
            "seeds": list(range(10)),
            "max_steps": 60,
            "policies": ["planner", "random", "rl"],
        },
        {
            "name": "localization-lab",
            "env": "bounce_gym/BounceLocalization-v0",
            "env_kwargs": {"angles": [45, 135]},
            "seeds": [0, 1, 2, 3, 4, 5, 6, 7],
            "max_steps": 200,
            "policies": ["planner", "random", "fixed"],
        },
        {
            "name": "multirobot-coverage-10x10",
            "env": "bounce_gym/MultiBounceCoverage-v0",
            "env_kwargs": {"world": "grid_10x10", "n_robots": 3, "backend": "cell",
                           "step_mode": "tick", "angles": [45, 90, 135],
                           "corner_rule": "no_squeeze", "robot_collisions": "bounce",
                           "turn_angles": [45, -45]},
            "seeds": [0, 1, 2, 3, 4],
            "max_steps": 5000,
            "policies": ["planner", "random", "rl"],
            "planner_kwargs": {"phi": 135},
            "rl_models": "multirobot-coverage",
        },
        {
            "name": "multirobot-monitoring-15x15",
            "env": "bounce_gym/MultiBounceMonitoring-v0",
            "env_kwargs": {"world": "grid_15x15", "n_robots": 2, "backend": "cell",
                           "step_mode": "tick", "angles": [45, 90, 135],
                           "corner_rule": "no_squeeze", "robot_collisions": "ignore",
                           "task_kwargs": {"regions": [
                               [[0, 0], [7.5, 0], [7.5, 15], [0, 15]],
                               [[7.5, 0], [15, 0], [15, 15], [7.5, 15]]]}},
            "seeds": [0, 1, 2, 3, 4],
            "max_steps": 300,
            "policies": ["planner", "random", "rl"],
            "planner_kwargs": {"phi": 90},
            "rl_models": "multirobot-monitoring",
        },
    ],
}

_TOP_KEYS = {"name": str, "output": str, "models": str, "experiments": list}
_EXPERIMENT_KEYS = {"name": str, "env": str, "env_kwargs": dict, "seeds": list,
                    "max_steps": int, "policies": list, "visibility": dict,
                    "planner_kwargs": dict, "rl_models": str}


def validate_config(config: object) -> dict:
    """Check a configuration; raise `ConfigError` naming the key and what is allowed."""
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
        if is_multi(exp["env"]):
            validate_multi_experiment(where, exp)
        elif exp["env"] not in gym.registry:
            known = sorted(i for i in gym.registry if i.startswith("bounce_gym/"))
            raise ConfigError(f"{where}.env: unknown environment id {exp['env']!r}; registered: "
                              f"{known + list(MULTI_ENV_IDS)}")
        elif "planner_kwargs" in exp:
            raise ConfigError(f"{where}.planner_kwargs: only for multi-robot experiments "
                              f"(env one of {list(MULTI_ENV_IDS)})")
        if "rl_models" in exp and (Path(exp["rl_models"]).name != exp["rl_models"]
                                   or exp["rl_models"] in ("", ".", "..")):
            raise ConfigError(f"{where}.rl_models: expected the name of a folder in models/, "
                              f"got {exp['rl_models']!r}")
        if not all(isinstance(s, int) and not isinstance(s, bool) for s in exp["seeds"]):
            raise ConfigError(f"{where}.seeds: expected a list of integers, got {exp['seeds']!r}")
        if exp["max_steps"] < 1:
            raise ConfigError(f"{where}.max_steps: expected an integer >= 1")
        unknown = [p for p in exp["policies"] if p not in POLICY_KINDS]
        if unknown:
            raise ConfigError(f"{where}.policies: unknown {unknown}; allowed are {POLICY_KINDS}")
    return config


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


@dataclass
class EpisodeResult:
    """One row of the results table."""

    experiment: str
    policy: str
    seed: int
    steps: int
    ticks: int
    episode_return: float
    metrics: dict = field(default_factory=dict)

    def row(self) -> dict:
        return {"experiment": self.experiment, "policy": self.policy, "seed": self.seed,
                "steps": self.steps, "ticks": self.ticks, "return": self.episode_return,
                **self.metrics}


def make_env(experiment: Mapping, **extra) -> gym.Env:
    return gym.make(experiment["env"], **experiment["env_kwargs"], **extra)


def policies_for(experiment: Mapping, env: gym.Env, models_dir: Path) -> list[Policy]:
    """The policies of an experiment that apply to its environment."""
    out: list[Policy] = []
    task = env.unwrapped.task.name
    angles = env.unwrapped.options.angles[0]
    discrete = env.unwrapped.options.action_type == "discrete"
    scenario = experiment.get("_scenario")
    for kind in experiment["policies"]:
        if kind == "planner" and scenario is not None:
            out.append(scenario.planner(seed=0))
        elif kind == "planner" and discrete:
            out.append(reference_policy(task, env))
        elif kind == "random":
            out.append(RandomAnglePolicy(seed=0))
        elif kind == "fixed" and discrete:
            out += [FixedAnglePolicy(i, math.degrees(a)) for i, a in enumerate(angles)]
        elif kind == "rl":
            out += rl_policies(models_dir / experiment.get("rl_models", experiment["name"]))
    return out


def reference_policy(task: str, env: gym.Env) -> Policy:
    """The analytic planner of a task, as a policy."""
    factories: dict[str, Callable[[gym.Env], Policy]] = {
        "navigation": _navigation_planner,
        "coverage": _coverage_planner,
        "localization": _localization_planner,
    }
    if task not in factories:
        raise ConfigError(f"policies: no reference planner for task {task!r}")
    return factories[task](env)


def _localization_planner(env: gym.Env) -> Policy:
    from baselines.localization import AngleSwitchPolicy

    return AngleSwitchPolicy.for_env(env)


def _navigation_planner(env: gym.Env) -> Policy:
    from baselines.navigation import NavigationPlanner

    return NavigationPlanner()


def _coverage_planner(env: gym.Env) -> Policy:
    from baselines.coverage import MixturePolicy

    return MixturePolicy.for_env(env)


class SB3Policy(Policy):
    """A trained Stable-Baselines3 model as a policy (deterministic actions)."""

    def __init__(self, path: Path) -> None:
        from sb3_contrib import RecurrentPPO
        from stable_baselines3 import DQN, PPO

        algos = {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}
        algo = path.stem.split("_")[0].lower()
        if algo not in algos:
            raise ConfigError(f"model {path}: name must start with one of {sorted(algos)}")
        self.model = algos[algo].load(path, device="cpu")
        self.name = f"rl {path.stem}"
        self.recurrent = algo == "recurrentppo"

    def reset(self, env) -> None:
        self.state = None
        self.start = np.ones((1,), dtype=bool)
        self.discrete = isinstance(env.action_space, gym.spaces.Discrete)

    def act(self, observation, info):
        action, self.state = self.model.predict(observation, state=self.state,
                                                episode_start=self.start, deterministic=True)
        self.start = np.zeros((1,), dtype=bool)
        return int(np.asarray(action).item()) if self.discrete else np.asarray(action)


def rl_policies(folder: Path) -> list[Policy]:
    return [SB3Policy(path) for path in sorted(folder.glob("*.zip"))] if folder.is_dir() else []


def run_episode(env: gym.Env, policy: Policy, seed: int, max_steps: int,
                scenario=None) -> tuple[dict, list]:
    """One episode; returns the summary and the trajectory (positions after every step).

    With a visibility ``scenario`` the episode starts on its start segment; the scenario says
    when it is done (goal segment reached) and whether it succeeded.
    """
    options = scenario.start_options(np.random.default_rng(seed)) if scenario else None
    obs, info = env.reset(seed=seed, options=options)
    policy.reset(env)
    total, steps = 0.0, 0
    path = [np.array(info["position"], dtype=float)]
    terminated = truncated = reached = False
    while not (terminated or truncated or reached) and steps < max_steps:
        obs, reward, terminated, truncated, info = env.step(policy.act(obs, info))
        total += reward
        steps += 1
        path.append(np.array(info["position"], dtype=float))
        reached = scenario is not None and scenario.done(info)
    summary = {"info": info, "return": total, "steps": steps, "terminated": terminated}
    if scenario is not None:
        summary["scenario_success"] = scenario.success(info)
    return summary, path


def task_metrics(task: str, summary: dict, policy: Policy) -> dict:
    info = summary["info"]
    if task == "navigation":
        out = {"success": bool(info.get("is_success", False))}
        if "ticks_to_goal" in info:
            out["ticks_to_goal"] = info["ticks_to_goal"]
        for key in ("predicted_ticks", "predicted_weight"):
            value = getattr(policy, key, None)
            if value is not None:
                out[key] = value
        return out
    if task == "coverage":
        return {"coverage": info["coverage"], "distance": info["distance"],
                "tv_distance": info["tv_distance"]}
    if task == "localization":
        return {"success": bool(info.get("localized", False)),
                "candidates": int(info.get("candidates", -1))}
    return {}


def run(config: Mapping, progress: bool = True) -> tuple[list[EpisodeResult], dict]:
    """Run every experiment of a (validated) configuration.

    Returns the result rows and, per experiment, the data for plots (trajectories, coverage
    histograms and targets, mixture weights; for multi-robot experiments see
    `experiments.multi_evaluation.run_multi_experiment`).
    """
    from tqdm import tqdm

    config = validate_config(config)
    models = Path(config["models"])
    rows: list[EpisodeResult] = []
    plots: dict = {}
    total = sum(len(exp["seeds"]) for exp in config["experiments"])
    with tqdm(total=total, desc="evaluating", disable=not progress, unit="seed") as bar:
        for exp in config["experiments"]:
            if is_multi(exp["env"]):
                episodes, plots[exp["name"]] = run_multi_experiment(exp, models, bar.update)
                rows += [EpisodeResult(exp["name"], policy, seed, e["steps"], e["ticks"],
                                       e["return"], e["metrics"])
                         for policy, seed, e in episodes]
                continue
            for seed in exp["seeds"]:
                _run_single_seed(exp, seed, models, rows, plots)
                bar.update()
    return rows, plots


def _run_single_seed(exp: Mapping, seed: int, models: Path, rows: list, plots: dict) -> None:
    """Every policy of a single-robot experiment on one seed; appends rows and plot data."""
    env = make_env(exp)
    task = env.unwrapped.task.name
    scenario = None
    if "visibility" in exp:
        from baselines.visibility.scenario import VisibilityScenario

        scenario = VisibilityScenario.for_experiment(env, exp["visibility"])
        exp = {**exp, "_scenario": scenario}
    for policy in policies_for(exp, env, models):
        summary, path = run_episode(env, policy, seed, exp["max_steps"], scenario)
        ticks = int(summary["info"]["ticks"])
        metrics = task_metrics(task, summary, policy)
        if scenario is not None:
            metrics["success"] = summary["scenario_success"]
        rows.append(EpisodeResult(exp["name"], policy.name, seed, summary["steps"], ticks,
                                  float(summary["return"]), metrics))
        data = plots.setdefault(exp["name"], {"world": env.unwrapped.world, "task": task,
                                              "paths": {}, "coverage": {},
                                              "visibility": scenario})
        data["paths"].setdefault(policy.name, np.array(path))
        if task == "coverage":
            core_task = env.unwrapped.task
            data["coverage"].setdefault(policy.name, core_task.visits.copy())
            data["target"] = core_task.target
            if hasattr(policy, "alpha"):
                data["alpha"] = (policy.alpha, [math.degrees(a) for a in
                                                env.unwrapped.options.angles[0]])
    env.close()


def summarise(rows: list[EpisodeResult]) -> list[dict]:
    """Per (experiment, policy): the mean and the population standard deviation (``<key>_std``)
    of every numeric column, over the episodes that have it (``ticks_to_goal`` exists only for
    successful episodes, ``steps_to_full`` only for episodes that reached full coverage).

    A column whose values are all the same integer (``robots``) stays that integer. Where
    episodes report ``steps_to_full``, ``full`` counts those that reached full coverage.
    """
    groups: dict[tuple[str, str], list[dict]] = {}
    for r in rows:
        groups.setdefault((r.experiment, r.policy), []).append(r.row())
    out = []
    for (exp, policy), items in groups.items():
        entry = {"experiment": exp, "policy": policy, "episodes": len(items)}
        keys = list(dict.fromkeys(k for item in items for k in item))
        for key in keys:
            if key in ("experiment", "policy", "seed"):
                continue
            values = [i[key] for i in items if key in i and i[key] is not None]
            if values and all(isinstance(v, bool | int | float | np.floating) for v in values):
                numbers = np.array([float(v) for v in values])
                constant_int = all(isinstance(v, int) and not isinstance(v, bool) and v == values[0]
                                   for v in values)
                entry[key] = values[0] if constant_int else float(numbers.mean())
                entry[f"{key}_std"] = float(numbers.std())
        if "steps_to_full" in keys:
            entry["full"] = sum(i.get("steps_to_full") is not None for i in items)
        out.append(entry)
    return out
