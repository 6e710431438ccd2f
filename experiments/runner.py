"""Running experiments: one episode loop and one experiment loop for Gymnasium envs (one robot)
and PettingZoo parallel envs (several robots).

An experiment builds its env and its policies once; every seed then runs one episode of each
policy (the env is reset with the seed, and each policy restarts its own random stream in
`start_options`, so an episode never depends on the ones before it). The experiment's family
(`experiments.registry`) supplies the planner, follows the episode for its metrics and collects
the first seed's plot data. Results are one `EpisodeResult` per (experiment, policy, seed):
steps, ticks, the return (summed over robots) and the family's metrics.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np

from baselines.policy import FixedAnglePolicy, Policy, RandomAnglePolicy, is_parallel_env
from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym.errors import ConfigError, config_errors
from experiments.config import validate_config
from experiments.families.base import Episode, Family
from experiments.registry import family_for


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


def make_env(experiment: Mapping, where: str = "env_kwargs"):
    """The experiment's env: ``gym.make``, or for a PettingZoo id the parallel env with
    ``max_cycles = max_steps``. Bad ``env_kwargs`` raise `ConfigError` naming ``where``."""
    with config_errors(where):
        if is_pettingzoo_id(experiment["env"]):
            import pettingzoo

            return pettingzoo.make("parallel", experiment["env"],
                                   max_cycles=experiment["max_steps"], **experiment["env_kwargs"])
        return gym.make(experiment["env"], **experiment["env_kwargs"])


def policies_for(experiment: Mapping, env, family: Family, setup: object,
                 models_dir: Path) -> list[Policy]:
    """The experiment's policies that apply to its env.

    The random policy of a single-robot experiment draws from the stream of seed 0 in every
    episode; with several robots it draws from the episode's seed.
    """
    from baselines.rl.policies import sb3_policies

    parallel = is_parallel_env(env)
    options = env.unwrapped.options
    discrete = options.action_type == "discrete"
    if parallel and not discrete:
        raise ConfigError("env_kwargs.action_type: multi-robot experiments choose angles by index; "
                          "use 'discrete'")
    out: list[Policy] = []
    for kind in experiment["policies"]:
        if kind == "planner":
            planner = family.planner(env, experiment, setup)
            out += [planner] if planner is not None else []
        elif kind == "random":
            out.append(RandomAnglePolicy(seed=None if parallel else 0))
        elif kind == "fixed" and discrete:
            n = min(len(phi) for phi in options.angles)
            out += [FixedAnglePolicy(i, math.degrees(options.angles[0][i])) for i in range(n)]
        elif kind == "rl":
            folder = models_dir / experiment.get("rl_models", experiment["name"])
            out += sb3_policies(folder, env)
    return out


def run_episode(env, policy: Policy, seed: int, max_steps: int, episode: Episode | None = None,
                record: bool = False) -> tuple[dict, np.ndarray | None]:
    """One episode of ``policy`` (the `baselines.policy.Policy` call order), at most
    ``max_steps`` steps, ended early by the env or by ``episode`` (the family's follower).

    Returns ``{"steps", "ticks", "return", "info"}`` (``info``: the last one, robot 0's in a
    parallel env) and, with ``record``, the positions (steps + 1, m, 2) of every robot.
    """
    episode = Episode() if episode is None else episode
    parallel = is_parallel_env(env)
    options = policy.start_options(env, seed)
    imposed = episode.start_options(seed)
    obs, infos = env.reset(seed=seed, options=options if imposed is None else imposed)
    policy.reset(env)
    info = _first_info(env, infos)
    path = [_positions(env, infos)] if record else None
    over = episode.start(info)
    steps, total, env_done = 0, 0.0, False
    while not (env_done or over) and steps < max_steps:
        obs, reward, terminated, truncated, infos = env.step(policy.act(obs, infos))
        steps += 1
        if parallel:
            total += float(sum(reward.values()))
            env_done = not env.agents
        else:
            total += reward
            env_done = terminated or truncated
        info = _first_info(env, infos)
        if record:
            path.append(_positions(env, infos))
        over = episode.step(info)
    summary = {"steps": steps, "ticks": int(info["ticks"]), "return": float(total), "info": info}
    return summary, None if path is None else np.array(path)


def _first_info(env, infos: dict) -> dict:
    return next(iter(infos.values())) if is_parallel_env(env) else infos


def _positions(env, infos: dict) -> np.ndarray:
    """Every robot's position (m, 2)."""
    if is_parallel_env(env):
        return np.array([infos[a]["position"] for a in env.possible_agents], dtype=float)
    return np.array(infos["position"], dtype=float).reshape(1, 2)


@dataclass
class Prepared:
    """A validated experiment with its env, family, the family's setup and its policies."""

    experiment: Mapping
    env: object
    family: Family
    setup: object
    policies: list[Policy]


def prepare_experiment(experiment: Mapping, models_dir: Path, where: str) -> Prepared:
    """Build a validated experiment's env, planner setup and policies (loading its models), so
    that every mistake in it is reported before any episode runs; ``where`` names the
    experiment in errors."""
    env = make_env(experiment, f"{where}.env_kwargs")
    family = family_for(experiment, env)
    setup = family.prepare(env, experiment)
    return Prepared(experiment, env, family, setup,
                    policies_for(experiment, env, family, setup, models_dir))


def run_experiment(prepared: Prepared, on_seed: Callable[[], None]
                   ) -> tuple[list[EpisodeResult], dict]:
    """Every policy on every seed of a prepared experiment (`prepare_experiment`).

    Returns the rows and the plot data: ``world``, ``family``, each policy's first-seed
    positions (``paths``) and what the family collects. ``on_seed`` is called after each seed
    (a progress bar).
    """
    rows: list[EpisodeResult] = []
    experiment, env, family = prepared.experiment, prepared.env, prepared.family
    setup, policies = prepared.setup, prepared.policies
    data: dict = {"paths": {}, "world": env.unwrapped.options.world, "family": family}
    for k, seed in enumerate(experiment["seeds"]):
        for policy in policies:
            episode = family.episode(env, policy, setup)
            summary, path = run_episode(env, policy, seed, experiment["max_steps"], episode,
                                        record=k == 0)
            rows.append(EpisodeResult(experiment["name"], policy.name, seed, summary["steps"],
                                      summary["ticks"], summary["return"],
                                      family.row_metrics(episode, summary["info"], policy)))
            if k == 0:
                data["paths"][policy.name] = path
                family.collect(data, env, policy, setup)
        on_seed()
    env.close()
    return rows, data


def run(config: Mapping, progress: bool = True) -> tuple[list[EpisodeResult], dict]:
    """Run every experiment of a configuration (validated here). Every experiment is prepared
    (`prepare_experiment`) before the first one runs.

    Returns the result rows and, per experiment name, its plot data (see `run_experiment`).
    """
    from tqdm import tqdm

    config = validate_config(config)
    models = Path(config["models"])
    rows: list[EpisodeResult] = []
    plots: dict = {}
    total = sum(len(exp["seeds"]) for exp in config["experiments"])
    prepared = [prepare_experiment(exp, models, f"config.experiments[{k}]")
                for k, exp in enumerate(config["experiments"])]
    with tqdm(total=total, desc="evaluating", disable=not progress, unit="seed") as bar:
        for one in prepared:
            episodes, plots[one.experiment["name"]] = run_experiment(one, bar.update)
            rows += episodes
    return rows, plots
