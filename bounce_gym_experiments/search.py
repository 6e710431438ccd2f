"""Hyperparameter search with Ray Tune: ``bounce-gym tune config.yaml``.

Each trial is a training run of the configuration (its first seed) with hyperparameters drawn
from a search space (`bounce_gym_experiments.search_space`; by default
``hyperparams/search/<algo>.yaml`` beside the configuration) over the configuration's own and its
hyperparameter file's. Trial ``k`` is the run ``<algo>[-<variant>]-trial<k>`` in
``<models>/<name>-tune/``: its model, checkpoints, monitor file and manifest entries are those of
any training run (`baselines.rl.train`), so ``bounce-gym curves`` draws the trials and the
evaluation can score them.

**The metric** is what the learning curves show at the end of a run: the mean over the last
100 episodes of the monitor file (`baselines.rl.curves.WINDOW`) of the return (``return``) or of
``is_success`` (``success``, for envs that report it). Every trial reports it to Tune as it
trains (at the end of a rollout, at most ten times a run, once an episode has finished) and
when it ends; ASHA (``--scheduler asha``) compares the trials at the same env steps and stops
the worst early: a stopped trial keeps its checkpoints but saves no model.

**Seeds** (`baselines.seeds`). A trial trains with the configuration's first seed s, its
envs seeded s, s + 1, … (training seeds, checked like any training run's), and its metric is
read from those same training episodes. No trial plays an episode on a tuning or an evaluation
seed, so the evaluation of the chosen hyperparameters stays on episodes no choice was made on.

**Outputs**, besides the runs: ``trials.csv`` (one row per trial: its status, the metric,
episodes and env steps, and its hyperparameters) and ``best_hyperparams.yaml``, the best
finished trial's complete entry in rl-zoo's layout, keyed by env id, to paste into
``configs/hyperparams/<algo>.yaml``. Tune's own records go to ``ray/`` in the same folder.

Ray runs the trials, one CPU each, at most ``workers`` at once: a local instance started here
(``num_cpus = workers``, default the machine's cores), or the cluster at ``address``, whose
nodes must see the models folder at the same path (a shared file system). The draws are made
here, not by Tune, so trial k has the same hyperparameters on every machine.

**Settings**, checked before the configuration is read (`check_search`): ``--metric``
``return`` or ``success``; ``--scheduler`` ``fifo`` or ``asha``; ``--workers`` in [1, 1024];
``--address`` a Ray address as `bounce_gym_experiments.executors` describes them, whose cluster answers
within its ``CONNECT_TIMEOUT``. Then, before the search space is read (`trial_configs`):
``--trials`` in [1, `MAX_TRIALS` = 10,000], ``--seed`` in [0, 2**32 - 1] and the
configuration's ``name`` at most 95 bytes (its folder's name adds ``-tune``). The search
space's bounds are checked against the hyperparameters' ranges (`bounce_gym_experiments.search_space`),
and then every trial is prepared, so that no mistake waits for a trial to start.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from baselines.rl.curves import WINDOW
from baselines.rl.monitor import read_monitor
from baselines.rl.train import RunFiles, finished, prepare, train_seed
from baselines.rl.train_config import POLICIES
from bounce_gym.errors import ConfigError
from bounce_gym.extras import require
from bounce_gym.files import MAX_NAME_BYTES, atomic_write
from bounce_gym.validate import integer
from bounce_gym_experiments.executors import check_ray_cluster, executor_settings, init_ray
from bounce_gym_experiments.search_space import load_search_space, sample_trial

#: The metrics a search maximises, and the monitor columns they average.
METRICS = {"return": "r", "success": "is_success"}
SCHEDULERS = ("fifo", "asha")
#: Most trials of one search, and the largest seed of its draws.
MAX_TRIALS = 10_000
MAX_DRAW_SEED = 2**32 - 1
#: Reports to Tune per trial (at most; at rollout ends).
REPORTS = 10
#: What the training name gets in the name of the search's folder.
TUNE_SUFFIX = "-tune"


@dataclass(frozen=True)
class Trial:
    """One trial's outcome, as ``trials.csv`` lists it."""

    index: int
    hyperparams: dict
    status: str
    metric: float
    episodes: int
    env_steps: int


def search_folder(config: Mapping) -> Path:
    """``<models>/<name>-tune``: where the trials of a configuration are saved."""
    return Path(config.get("models", "models")) / f"{config['name']}{TUNE_SUFFIX}"


def trial_configs(config: dict, space_path: Path, trials: int, seed: int,
                  folder: Path | None = None) -> list[tuple[dict, dict]]:
    """Each trial's drawn hyperparameters and its prepared training configuration
    (`baselines.rl.train.prepare`: every trial is checked before any starts); a mistake names
    the trial and what was drawn for it. ``trials`` is at most `MAX_TRIALS`, ``seed`` (of the
    draws) at most `MAX_DRAW_SEED`."""
    integer("--trials", trials, 1, MAX_TRIALS)
    integer("--seed", seed, 0, MAX_DRAW_SEED)
    if not isinstance(config, dict):
        prepare(config, folder)  # reports what is wrong with it
    _check_room_for_suffix(config.get("name"))
    space = load_search_space(space_path)
    base = {**config, "name": f"{config['name']}{TUNE_SUFFIX}",
            "models": str(Path(config.get("models", "models")).resolve())}
    base.pop("seed", None)
    seeds = config.get("seeds", [config.get("seed", 0)])
    base["seeds"] = seeds[:1] if isinstance(seeds, list) else seeds
    out = []
    for k in range(trials):
        drawn = sample_trial(space, seed, k)
        variant = f"{config['variant']}-trial{k}" if config.get("variant") else f"trial{k}"
        trial = {**base, "variant": variant,
                 "hyperparams": {**config.get("hyperparams", {}), **drawn}}
        try:
            out.append((drawn, prepare(trial, folder)))
        except ConfigError as exc:
            raise ConfigError(f"search: trial {k} ({drawn}): {exc}") from None
    return out


def _check_room_for_suffix(name: object) -> None:
    """The search's folder is ``<name>-tune``: a name that is one path component only without
    the suffix is refused for what it is (the name's other checks come with the
    configuration's)."""
    most = MAX_NAME_BYTES - len(TUNE_SUFFIX)
    if isinstance(name, str) and most < len(name.encode("utf-8")) <= MAX_NAME_BYTES:
        raise ConfigError(f"config.name: a search saves into models/<name>{TUNE_SUFFIX}, so the "
                          f"name may have at most {most} bytes; it has "
                          f"{len(name.encode('utf-8'))}")


def check_search(metric: str, scheduler: str, workers: int | None,
                 address: str | None) -> None:
    """How ``bounce-gym tune`` runs its trials, checked before anything is read or prepared
    (module docstring, "Settings"; `trial_configs` checks ``--trials`` and ``--seed``); a
    mistake is a `ConfigError` naming the flag."""
    if metric not in METRICS:
        raise ConfigError(f"--metric: expected one of {list(METRICS)}, got {metric!r}")
    if scheduler not in SCHEDULERS:
        raise ConfigError(f"--scheduler: expected one of {list(SCHEDULERS)}, got "
                          f"{scheduler!r}")
    executor_settings({"kind": "ray", "workers": workers, "address": address}, "tune",
                      {"workers": "--workers", "address": "--address"})
    if address is not None:
        check_ray_cluster("--address", address)


def default_space(config_path: Path, config: object) -> Path:
    """``hyperparams/search/<algo>.yaml`` beside the configuration file."""
    algo = config.get("algo", "ppo") if isinstance(config, dict) else "ppo"
    return config_path.parent / "hyperparams" / "search" / f"{algo}.yaml"


def final_metric(monitor: Path, metric: str) -> tuple[float, int, int]:
    """``(metric, episodes, env steps)`` of a monitor file: the metric's mean over its last
    `WINDOW` episodes (NaN before the first episode, or without the column)."""
    if not monitor.is_file():
        return math.nan, 0, 0
    columns = read_monitor(monitor)
    values = columns.get(METRICS[metric], np.array([]))
    episodes = len(columns["l"])
    steps = int(columns["steps"][-1]) if episodes else 0
    return (float(values[-WINDOW:].mean()) if len(values) else math.nan), episodes, steps


def run_trial(params: dict, configs: list[dict], metric: str) -> None:
    """A Tune trainable: train trial ``params["trial"]``, reporting the metric as it goes."""
    from ray import tune
    from stable_baselines3.common.callbacks import BaseCallback

    config = configs[params["trial"]]
    seed = config["seeds"][0]
    monitor = RunFiles(config, seed).monitor
    every = max(config["total_timesteps"] // REPORTS, 1)

    def report(steps: int) -> None:
        value, episodes, _ = final_metric(monitor, metric)
        tune.report({metric: value, "episodes": episodes, "env_steps": steps})

    class Report(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.next = every

        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:
            # never at the budget: a scheduler stops a trial that reports it (max_t) in the
            # report, and the model is saved after it
            if self.next <= self.num_timesteps < config["total_timesteps"] and \
                    final_metric(monitor, metric)[1]:
                self.next = self.num_timesteps + every
                report(self.num_timesteps)

    if not (config["resume"] and finished(config, seed)):
        train_seed(config, seed, progress=False, callbacks=[Report()])
    report(config["total_timesteps"])


def tune_search(prepared: list[tuple[dict, dict]], metric: str = "return",
                scheduler: str = "fifo", workers: int | None = None, address: str | None = None,
                progress: bool = True) -> list[Trial]:
    """Run the trials (`trial_configs`) on Ray Tune and write ``trials.csv`` and
    ``best_hyperparams.yaml``; returns the trials in order."""
    configs = [config for _, config in prepared]
    check_search(metric, scheduler, workers, address)
    require("bounce-gym tune (Ray Tune)", "ray")
    import ray
    from ray import tune
    from ray.tune.schedulers import ASHAScheduler

    folder = Path(configs[0]["models"]) / configs[0]["name"]
    # a local instance's workers import this very package, wherever it is
    root = str(Path(__file__).resolve().parents[1])
    paths = os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))
    started = init_ray("--address", address, workers or os.cpu_count(),
                       runtime_env={"env_vars": {"PYTHONPATH": paths}})
    try:
        total = configs[0]["total_timesteps"]
        asha = ASHAScheduler(time_attr="env_steps", max_t=total, grace_period=max(total // 4, 1),
                             reduction_factor=2) if scheduler == "asha" else None
        tuner = tune.Tuner(
            tune.with_resources(tune.with_parameters(run_trial, configs=configs, metric=metric),
                                {"cpu": 1}),
            param_space={"trial": tune.grid_search(list(range(len(configs))))},
            tune_config=tune.TuneConfig(metric=metric, mode="max", scheduler=asha,
                                        max_concurrent_trials=workers,
                                        trial_name_creator=_trial_name,
                                        trial_dirname_creator=_trial_name),
            run_config=tune.RunConfig(name="ray", storage_path=str(folder.resolve()),
                                      verbose=1 if progress else 0))
        grid = tuner.fit()
        errors = {Path(r.path).name: r.error for r in grid if r.error is not None}
    finally:
        if started:
            ray.shutdown()
    trials = [_outcome(k, drawn, config, metric, errors.get(f"trial_{k}"))
              for k, (drawn, config) in enumerate(prepared)]
    write_trials(folder, trials, metric)
    write_best(folder, configs, trials, metric)
    return trials


def _trial_name(trial) -> str:
    """Tune's name and folder of a trial: ``trial_<k>``."""
    return f"trial_{trial.config['trial']}"


def _outcome(k: int, drawn: dict, config: dict, metric: str,
             error: BaseException | None) -> Trial:
    run = RunFiles(config, config["seeds"][0])
    value, episodes, steps = final_metric(run.monitor, metric)
    if finished(config, run.seed):
        status = "finished"
    elif error is not None:
        last = (str(error).strip().splitlines() or [""])[-1]
        status = f"failed: {type(error).__name__}: {last}"
    else:
        status = "stopped early"
    return Trial(k, drawn, status, value, episodes, steps)


def best(trials: list[Trial]) -> Trial | None:
    """The finished trial with the highest metric (the first of equals), or None."""
    done = [t for t in trials if t.status == "finished" and not math.isnan(t.metric)]
    return max(done, key=lambda t: t.metric) if done else None


def write_trials(folder: Path, trials: list[Trial], metric: str) -> Path:
    """``trials.csv``: trial, status, the metric, episodes, env steps, then the hyperparameters
    (sorted by name; mappings and lists as YAML flow text)."""
    keys = sorted({key for t in trials for key in t.hyperparams})
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["trial", "status", metric, "episodes", "env_steps", *keys])
    for t in trials:
        writer.writerow([t.index, t.status, f"{t.metric:.6g}", t.episodes, t.env_steps,
                         *(_cell(t.hyperparams.get(key, "")) for key in keys)])
    path = folder / "trials.csv"
    atomic_write(path, out.getvalue().encode())
    return path


def _cell(value: object) -> str:
    if isinstance(value, dict | list):
        return yaml.safe_dump(value, default_flow_style=True).strip()
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def write_best(folder: Path, configs: list[dict], trials: list[Trial], metric: str) -> Path | None:
    """``best_hyperparams.yaml``: the best trial's entry in rl-zoo's layout (none if no trial
    finished)."""
    winner = best(trials)
    if winner is None:
        return None
    config = configs[winner.index]
    key = config["env"] if "role" not in config else f"{config['env']}:{config['role']}"
    entry = {"n_timesteps": config["total_timesteps"], "policy": POLICIES[config["algo"]],
             "n_envs": config["n_envs"]}
    if config["n_stack"] > 1:
        entry["frame_stack"] = config["n_stack"]
    if config["normalize"] is not None:
        entry["normalize"] = config["normalize"]
    entry.update(config["hyperparams"])
    header = (f"# bounce-gym tune: trial {winner.index} of {len(trials)}, {metric} "
              f"{winner.metric:.6g} over the last {WINDOW} episodes\n")
    path = folder / "best_hyperparams.yaml"
    atomic_write(path, (header + yaml.safe_dump({key: entry}, sort_keys=False)).encode())
    return path
