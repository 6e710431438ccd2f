"""Running experiments: one episode loop for Gymnasium envs (one robot) and PettingZoo parallel
envs (several robots), preparing an experiment, and `run`, which runs a configuration as a sweep
of units on an executor (`bounce_gym_experiments.sweep`, `bounce_gym_experiments.executors`).

An experiment builds its env and its policies once; every seed then runs one episode of each
policy (the env is reset with the seed, and each policy restarts its own random stream in
`start_options`, so an episode never depends on the ones before it). The experiment's family
(`bounce_gym_experiments.registry`) supplies the policies of each kind (the planner, the random and fixed
baselines), follows the episode for its metrics and clock, and collects the first seed's plot
data; nothing here assumes one kind of robot or task. Results are one `EpisodeResult` per (experiment,
policy, seed): steps, ticks, the return (summed over robots) and the family's metrics; with two
or more fixed angles, also the best of them per seed in hindsight (`bounce_gym_experiments.oracle`).

Trained models are loaded from the experiment's ``rl_models`` folders; a folder with other
observation options runs its models on its own copy of the env (same world, same seeds, same
episodes). Each model is two policies: its sampled actions (``rl <algo>_seed<N>``,
``rl <folder>/<algo>_seed<N>`` when there are several folders) and its greedy ones (the same
name and ``(greedy)``, `Family.trained_policies`), whose rows carry the ``group`` they are
aggregated into (``rl <algo>`` and ``rl <algo> (greedy)``: one row each per algorithm over its
training seeds, `bounce_gym_experiments.report.table_rows`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np

from baselines.policy import Policy, is_parallel_env, labelled
from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym.errors import config_errors
from bounce_gym.extras import missing_extra
from bounce_gym_experiments.config import training_configs_for, validate_config
from bounce_gym_experiments.executors import Executor, UnitStore, make_executor
from bounce_gym_experiments.families.base import Episode, Family, unplayable
from bounce_gym_experiments.registry import family_of


@dataclass
class EpisodeResult:
    """One row of the results table; ``group`` names the row it is aggregated into (trained
    models: ``rl <algo>``, over training seeds), ``None`` for a row of its own."""

    experiment: str
    policy: str
    seed: int
    steps: int
    ticks: int
    episode_return: float
    metrics: dict = field(default_factory=dict)
    group: str | None = None

    def row(self) -> dict:
        out = {"experiment": self.experiment, "policy": self.policy, "seed": self.seed,
               "steps": self.steps, "ticks": self.ticks, "return": self.episode_return,
               **self.metrics}
        if self.group is not None:
            out["group"] = self.group
        return out


def make_experiment_env(experiment: Mapping, where: str = "env_kwargs", overrides: Mapping | None = None):
    """The experiment's env with its horizon ``max_steps`` as the env's own limit:
    ``gym.make(..., max_episode_steps=max_steps)``, or for a PettingZoo id the parallel env with
    ``max_cycles = max_steps``. ``overrides`` are env options set over ``env_kwargs``. Bad
    ``env_kwargs`` raise `ConfigError` naming ``where``."""
    kwargs = {**experiment["env_kwargs"], **(overrides or {})}
    with config_errors(where):
        if is_pettingzoo_id(experiment["env"]):
            import pettingzoo

            return pettingzoo.make("parallel", experiment["env"],
                                   max_cycles=experiment["max_steps"], **kwargs)
        return gym.make(experiment["env"], max_episode_steps=experiment["max_steps"], **kwargs)


def policies_for(experiment: Mapping, env, family: Family, setup: object) -> list[Policy]:
    """The experiment's planner, random and fixed policies, as its family builds them for its
    env (trained models: `Family.trained_policies`)."""
    return [policy for kind in experiment["policies"] if kind != "rl"
            for policy in family.policies(kind, env, experiment, setup)]


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
    summary = {"steps": steps, "ticks": episode.ticks(info, steps), "return": float(total),
               "info": info}
    return summary, None if path is None else np.array(path)


def _first_info(env, infos: dict) -> dict:
    return next(iter(infos.values())) if is_parallel_env(env) else infos


def _positions(env, infos: dict) -> np.ndarray:
    """Every robot's position (m, 2)."""
    if is_parallel_env(env):
        return np.array([infos[a]["position"] for a in env.possible_agents], dtype=float)
    return np.array(infos["position"], dtype=float).reshape(1, 2)


@dataclass
class Entrant:
    """A policy of an experiment, the env it runs in, the family's setup on that env, and the
    row it is aggregated into (``None``: its own)."""

    policy: Policy
    env: object
    setup: object
    group: str | None = None


@dataclass
class Prepared:
    """A validated experiment with its env, family, the family's setup, its entrants, and for
    the report its warnings: rows the configuration asks for that cannot play (a model folder
    with no models, a learner whose extra is missing)."""

    experiment: Mapping
    env: object
    family: Family
    setup: object
    entrants: list[Entrant]
    warnings: list[str]


def _named(policy: Policy) -> Policy:
    """``policy`` with its information class in its name (`baselines.policy.labelled`)."""
    policy.name = labelled(policy.name, policy.information)
    return policy


def prepare_experiment(experiment: Mapping, models_dir: Path, where: str) -> Prepared:
    """Build a validated experiment's env, planner setup and policies (loading its models), so
    that every mistake in it is reported before any episode runs; ``where`` names the
    experiment in errors."""
    family = family_of(experiment, where)
    env = make_experiment_env(experiment, f"{where}.env_kwargs")
    setup = family.prepare(env, experiment)
    entrants = [Entrant(_named(p), env, setup)
                for p in policies_for(experiment, env, family, setup)]
    warnings = []
    if "rl" in experiment["policies"] or "rl" in experiment.get("adversaries", ()):
        folders = experiment["rl_models"]
        for k, entry in enumerate(folders):
            folder = models_dir / entry["folder"]
            own_env, own_setup = env, setup
            if entry["env_kwargs"]:
                own_env = make_experiment_env(experiment, f"{where}.rl_models[{k}].env_kwargs",
                                   entry["env_kwargs"])
                own_setup = family.prepare(own_env, experiment)
            label = f"{entry['folder']}/" if len(folders) > 1 else ""
            found = family.trained_policies(folder, own_env, label, experiment, own_setup)
            entrants += [Entrant(p, own_env, own_setup, group) for p, group in found]
            if left_out := unplayable(folder):
                warnings.append(f"{experiment['name']}: " + str(missing_extra(
                    f"playing the {len(left_out)} JAX models of {folder}", ["jax"]))
                    + "; they are left out")
            if not found:
                warnings.append(f"{experiment['name']}: no trained models in {folder} "
                             f"(<algo>_seed<N>.zip), so no rl rows; {_to_train(entry['folder'])}")
    return Prepared(experiment, env, family, setup, entrants, warnings)


def _to_train(folder: str) -> str:
    """What makes the models of ``folder``: the shipped training configurations of that name."""
    found = training_configs_for(folder)
    if not found:
        return "no shipped training configuration makes them"
    return "train them with " + " or ".join(f"`bounce-gym train {path}`" for path in found)


def run(config: Mapping, progress: bool = True, executor: Executor | None = None,
        store: UnitStore | None = None) -> tuple[list[EpisodeResult], dict]:
    """Run every experiment of a configuration (validated here) as a sweep of units
    (`bounce_gym_experiments.sweep`) on ``executor`` (default: one after another in this process),
    keeping finished units in ``store`` (default: a temporary folder). Every experiment is
    prepared (`prepare_experiment`) before the first unit runs.

    Returns the result rows — per experiment, per seed, per policy, then the best fixed angle
    per seed in hindsight — and, per experiment name, its data: ``world``, ``family``,
    ``notes``, each policy's first-seed positions (``paths``) and what the family collects for
    its plots. Units that fail for good raise `bounce_gym_experiments.sweep.UnitsFailedError`.
    """
    import tempfile

    from bounce_gym_experiments import sweep

    config = validate_config(config)
    experiments = sweep.prepare_all(config)
    try:
        executor = make_executor(workers=1) if executor is None else executor
        if store is not None:
            return sweep.run_sweep(config, experiments, executor, store, progress)
        with tempfile.TemporaryDirectory(prefix="bounce-gym-units-") as folder:
            return sweep.run_sweep(config, experiments, executor, UnitStore(Path(folder)),
                                  progress)
    finally:
        sweep.release(experiments)
