"""An evaluation as a sweep of independent units (`bounce_gym_experiments.executors`): one unit is one
policy of one experiment on a chunk of `SEEDS_PER_UNIT` consecutive seeds.

A unit's worker prepares the experiment from the validated configuration
(`bounce_gym_experiments.runner.prepare_experiment`, once per process and experiment: `prepared`) and runs
its policy on its seeds. The unit holding an experiment's first seed also collects that seed's
plot data, as the sequential loop did. The rows are then put in the canonical order —
experiment, seed, policy — and each experiment gets its best fixed angle in hindsight, so the
results do not depend on the executor, the number of workers or the order units finish in.

What episodes file with the experiment's setup for the plots (e.g. every coverage curve) is
taken out of the worker's copy with the unit's rows (`Family.drain`) and filed with this
process's setup in the canonical order (`Family.absorb`).

Finished units are kept in a `UnitStore` under ``<output>/<name>-units/<fingerprint>/``; the
fingerprint (`config_fingerprint`) covers the configuration without its executor, the manifests of its
model folders, the package version and the source commit, so that a sweep started again with
the same inputs skips the units already done, and one with other inputs starts afresh. Each
unit's `UnitResult` is kept as a pickle signed with the user's key, by the process that runs
the sweep (workers need no key), and read back only if the signature holds for that unit of
that fingerprint: a planted or foreign file is re-run, never unpickled
(`bounce_gym_experiments.executors.UnitStore`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from baselines.policy import FixedAnglePolicy
from bounce_gym.provenance import git_state, package_versions
from bounce_gym_experiments.executors import Executor, Unit, UnitFailure, UnitStore
from bounce_gym_experiments.oracle import best_fixed_in_hindsight
from bounce_gym_experiments.runner import EpisodeResult, Prepared, prepare_experiment, run_episode

#: seeds per unit: enough episodes to outweigh a unit's overhead, few enough to spread a
#: 20-seed experiment over several workers (docs/choices/studies.md)
SEEDS_PER_UNIT = 10


class _Setup:
    """Stands for the experiment's setup in a unit's plot data (each process has its own)."""


@dataclass
class UnitResult:
    """A unit's rows in seed order, what it collected for the plots (first-seed unit only,
    else ``None``) and what its episodes filed with the setup (`Family.drain`)."""

    rows: list[EpisodeResult]
    plot_data: dict | None
    drained: object


class UnitsFailedError(Exception):
    """Units of an evaluation failed for good; the finished ones are kept in ``store``."""

    def __init__(self, failures: list[UnitFailure], total: int, store: Path,
                 describe: Mapping[str, str]) -> None:
        self.failures, self.total, self.store = failures, total, store
        self.lines = [f"unit {f.key} ({describe[f.key]}) failed after {f.attempts} "
                      f"attempt{'s' if f.attempts > 1 else ''}: {f.error}" for f in failures]
        super().__init__("; ".join(self.lines))


#: this process's prepared experiments, by `_cache_key` (a worker prepares each once)
_PREPARED: dict[str, Prepared] = {}


def _cache_key(experiment: Mapping, models: str) -> str:
    """What an experiment is prepared from: all of it but its seeds (each unit carries its own
    few, so that a unit's arguments and this key stay small however many seeds there are)."""
    return json.dumps([{k: v for k, v in experiment.items() if k != "seeds"}, models],
                      sort_keys=True, default=str)


def prepared(experiment: Mapping, models: str, k: int) -> Prepared:
    """Experiment ``k`` of a validated configuration (``models``: its models folder), prepared
    once in this process."""
    key = _cache_key(experiment, models)
    if key not in _PREPARED:
        _PREPARED[key] = prepare_experiment(experiment, Path(models), f"config.experiments[{k}]")
    return _PREPARED[key]


def prepare_all(config: Mapping) -> list[Prepared]:
    """Every experiment of a validated configuration prepared here (so that every mistake is
    reported before any unit runs), and kept for the units that run in this process."""
    return [prepared(experiment, config["models"], k)
            for k, experiment in enumerate(config["experiments"])]


def release(experiments: list[Prepared]) -> None:
    """Close the envs of prepared experiments and forget them."""
    for one in experiments:
        envs = {id(e.env): e.env for e in one.entrants}
        envs[id(one.env)] = one.env
        for env in envs.values():
            env.close()
    keys = {id(one) for one in experiments}
    for key in [k for k, v in _PREPARED.items() if id(v) in keys]:
        del _PREPARED[key]


def run_unit(experiment: Mapping, models: str, k: int, entrant: int, seeds: list[int],
             first: bool) -> UnitResult:
    """Policy ``entrant`` of experiment ``k`` (without its seeds; ``models``: the models
    folder) on ``seeds``; with ``first`` (the chunk holding the experiment's first seed), that
    seed's plot data."""
    one = prepared(experiment, models, k)
    experiment, family, who = one.experiment, one.family, one.entrants[entrant]
    rows, plot_data = [], None
    for seed in seeds:
        record = first and seed == seeds[0]
        episode = family.episode(who.env, who.policy, who.setup)
        summary, path = run_episode(who.env, who.policy, seed, experiment["max_steps"], episode,
                                    record=record and family.record_paths)
        rows.append(EpisodeResult(experiment["name"], who.policy.name, seed, summary["steps"],
                                  summary["ticks"], summary["return"],
                                  family.row_metrics(episode, summary["info"], who.policy),
                                  who.group))
        if record:
            plot_data = {"paths": {who.policy.name: path}, "notes": []}
            family.collect(plot_data, who.env, who.policy, who.setup)
            plot_data = {key: _Setup() if value is who.setup else value
                         for key, value in plot_data.items()}
    return UnitResult(rows, plot_data, family.drain(who.setup))


def chunks(seeds: list[int]) -> list[list[int]]:
    """The seeds in consecutive chunks of `SEEDS_PER_UNIT`."""
    return [seeds[i:i + SEEDS_PER_UNIT] for i in range(0, len(seeds), SEEDS_PER_UNIT)]


def units(config: Mapping, experiments: list[Prepared]) -> tuple[list[Unit], dict[str, str]]:
    """The units of a validated configuration (``experiments``: its prepared experiments), in
    the canonical order, keyed ``<experiment>-<policy>-<chunk>`` by index, and what each is in
    words (for failures)."""
    out, describe = [], {}
    for k, one in enumerate(experiments):
        experiment = {key: v for key, v in one.experiment.items() if key != "seeds"}
        for e, who in enumerate(one.entrants):
            for j, seeds in enumerate(chunks(one.experiment["seeds"])):
                key = f"{k}-{e}-{j}"
                out.append(Unit(key, run_unit,
                                (experiment, config["models"], k, e, seeds, j == 0)))
                describe[key] = (f"experiment {one.experiment['name']}, policy "
                                 f"{who.policy.name}, seeds {seeds[0]}..{seeds[-1]}")
    return out, describe


def assemble_results(experiments: list[Prepared], results: Mapping[str, UnitResult]
             ) -> tuple[list[EpisodeResult], dict]:
    """The rows in the canonical order (experiment, seed, policy; then the best fixed angle in
    hindsight) and each experiment's plot data, from every unit's result."""
    rows: list[EpisodeResult] = []
    plots: dict = {}
    for k, one in enumerate(experiments):
        family = one.family
        data: dict = {"paths": {}, "world": family.world(one.env), "family": family,
                      "warnings": list(one.warnings), "notes": []}
        by_seed: dict[int, list[EpisodeResult]] = {s: [] for s in one.experiment["seeds"]}
        for e, who in enumerate(one.entrants):
            for j in range(len(chunks(one.experiment["seeds"]))):
                result = results[f"{k}-{e}-{j}"]
                for row in result.rows:
                    by_seed[row.seed].append(row)
                family.absorb(who.setup, result.drained)
                if result.plot_data is not None:
                    _merge_plot_data(data, result.plot_data, who.setup)
        own = [row for seed_rows in by_seed.values() for row in seed_rows]
        fixed = [e.policy.name for e in one.entrants if isinstance(e.policy, FixedAnglePolicy)]
        rows += own + best_fixed_in_hindsight(own, fixed, family)
        plots[one.experiment["name"]] = data
    return rows, plots


def _merge_plot_data(data: dict, part: dict, setup: object) -> None:
    """File one policy's first-seed plot data with the experiment's, as the sequential loop
    did: per-policy tables (``paths``, ``visits``, …) gain the policy's entry, a note is said
    once, any other value is the latest policy's; the setup is this process's."""
    for key, value in part.items():
        if isinstance(value, _Setup):
            data[key] = setup
        elif key == "notes":
            data["notes"] += [note for note in value if note not in data["notes"]]
        elif isinstance(value, dict) and isinstance(data.get(key), dict):
            data[key].update(value)
        else:
            data[key] = value


def config_fingerprint(config: Mapping) -> str:
    """What decides a validated configuration's results (module docstring), hashed: its
    experiments without the executor, its model folders' manifests, the package version and
    the source commit."""
    from baselines.rl.model_files import MANIFEST

    digest = hashlib.sha256()
    digest.update(json.dumps({k: v for k, v in config.items() if k != "executor"},
                             sort_keys=True, default=str).encode())
    for exp in config["experiments"]:
        for entry in exp.get("rl_models", []):
            manifest = Path(config["models"]) / entry["folder"] / MANIFEST
            digest.update(manifest.read_bytes() if manifest.is_file() else b"-")
    digest.update(json.dumps([package_versions()["bounce-gym"], git_state()["commit"]]).encode())
    return digest.hexdigest()[:16]


def store_folder(config: Mapping) -> Path:
    """Where a configuration's finished units are kept: ``<output>/<name>-units/<fingerprint>``."""
    return Path(config["output"]) / f"{config['name']}-units" / config_fingerprint(config)


def run_sweep(config: Mapping, experiments: list[Prepared], executor: Executor,
             store: UnitStore, progress: bool = True) -> tuple[list[EpisodeResult], dict]:
    """Run (or finish) the sweep of a validated configuration and assemble its rows and plot
    data; raise `UnitsFailedError` if units failed for good (the others are kept in ``store``)."""
    todo, describe = units(config, experiments)
    results, failures = executor.run(todo, store, progress=progress, desc="evaluating")
    if failures:
        raise UnitsFailedError(failures, len(todo), store.folder, describe)
    return assemble_results(experiments, results)
