"""Training sweeps: the seeds of a training configuration as units of an executor
(`bounce_gym_experiments.executors`), one training run (`baselines.rl.train.train_seed`) per unit.

The configuration is validated and checked once, here (`baselines.rl.train.prepare`), before any
unit starts. A unit is keyed by its run, ``<run>_seed<seed>``, and trains, or with ``resume``
continues from its newest checkpoint, that one seed; its model, checkpoints and monitor file are
exactly those of a run in one process, so the same seed gives the same weights on any executor.
The units of a sweep save into one folder at once; its manifest is updated under a lock
(`baselines.rl.model_files`).

**Started again** (``--resume``), a sweep skips the seeds whose model is saved for this
configuration and budget (`baselines.rl.train.finished`): the model files are the record of
what is done, so nothing else has to survive an interruption. A seed that was interrupted goes
on from its newest checkpoint; one that never saved a checkpoint starts afresh.

In this process (the local executor with one worker) a unit prints its lines and shows SB3's
progress bar as it trains, as training always has; on a pool or on Ray each unit's lines are
printed when the sweep ends, in seed order, under one progress bar over the units.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path

from baselines.rl.train import RunFiles, finished, prepare, train_seed
from bounce_gym.errors import ConfigError, OutputError
from bounce_gym_experiments.executors import (
    Executor,
    InProcessExecutor,
    Unit,
    UnitFailure,
    UnitStore,
    executor_settings,
    machine_cores,
    make_executor,
)


def executor_for(settings: Mapping, units: int) -> Executor:
    """The executor of checked ``executor`` settings (`bounce_gym_experiments.executors.executor_settings`)
    for a sweep of ``units`` units: the local executor's workers default to the machine's
    cores, but no more than there are units (one unit runs in this process)."""
    settings = dict(settings)
    if settings["kind"] == "local" and settings["workers"] is None:
        settings["workers"] = max(min(machine_cores(), units), 1)
    return make_executor(**settings)


def train_unit(config: Mapping, seed: int, live: bool, progress: bool) -> dict:
    """One unit of a sweep: train the seed of a prepared configuration. Returns the lines the
    run logged (printed as they come, with SB3's progress bar if ``progress``, when ``live``)
    and the model's path, or the `ConfigError` that stopped it: a mistake in the input (an env
    argument, a hyperparameter value SB3 refuses) is reported as one, not retried, and so is a
    write that failed (`OutputError`: a full disk, a folder that is not writable), which
    another attempt on the same disk would meet again after training as long."""
    lines: list[str] = []
    log = print if live else lines.append
    try:
        model = train_seed(config, seed, progress=live and progress, log=log)
    except (ConfigError, OutputError) as exc:
        return {"log": lines, "config_error": str(exc)}
    return {"log": lines, "model": str(model)}


def sweep(config: Mapping, executor: Mapping | None = None, folder: Path | None = None,
          progress: bool = True, log: Callable[[str], None] = print,
          ) -> tuple[list[Path], list[UnitFailure]]:
    """Train every seed of ``config`` (without its ``executor`` key) on the executor of the
    checked settings ``executor`` (`executor_for`; default: the local one; module docstring);
    ``folder`` is where a relative ``hyperparams_file`` is read from. Returns the saved models
    in seed order and the units that failed for good (the others complete)."""
    config = prepare(config, folder)
    todo = []
    for seed in config["seeds"]:
        if config["resume"] and finished(config, seed):
            log(f"{RunFiles(config, seed).stem}: already trained for {config['total_timesteps']} "
                f"steps ({RunFiles(config, seed).model})")
        else:
            todo.append(seed)
    runner = executor_for(executor or executor_settings({}), len(todo))
    live = isinstance(runner, InProcessExecutor)
    units = [Unit(RunFiles(config, seed).stem, train_unit, (config, seed, live, progress))
             for seed in todo]
    with tempfile.TemporaryDirectory(prefix="bounce-gym-units-") as store:
        results, failures = runner.run(units, UnitStore(Path(store)),
                                       progress=progress and not live,
                                       desc=f"{config['name']}: seeds")
    for unit in units:
        for line in results.get(unit.key, {}).get("log", []):
            log(line)
    for unit in units:
        if "config_error" in results.get(unit.key, {}):
            raise ConfigError(results[unit.key]["config_error"])
    paths = [RunFiles(config, seed).model for seed in config["seeds"]]
    failed = {f.key for f in failures}
    return [p for p in paths if p.name.removesuffix(".zip") not in failed], failures
