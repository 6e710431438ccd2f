"""An evaluation as a sweep of units (`bounce_gym_experiments.sweep`) on the local executors: the same
episodes.csv and results.json, byte for byte, in this process and on a pool of two; a sweep
killed mid-way and started again; a unit's worker that dies; a unit that fails for good; the
executor flags and config key (Ray: test_ray_executor.py).

Each test runs in its own ``tmp_path``. The one-process reference they compare with is made once
per test run (conftest.py: ``sweep_reference`` for the files, ``sweep_rows`` for the rows)."""

import os
import signal
import subprocess
import sys
import time

import pytest
import sweep_runs
import sweep_units
import yaml

from bounce_gym_experiments import sweep
from bounce_gym_experiments.config import validate_config
from bounce_gym_experiments.executors import Unit, UnitStore, make_executor
from bounce_gym_experiments.oracle import ORACLE_NAME
from bounce_gym_experiments.runner import run

sys.path.insert(0, str(sweep_runs.ROOT))
import evaluate  # noqa: E402


def _evaluate(folder, config, label, *flags):
    assert evaluate.main([str(config), "--no-progress", *flags]) == 0
    return sweep_runs.checksums(sweep_runs.take_run(folder, label))


@pytest.mark.slow  # a pool of two over the reference sweep: ~30 s
def test_a_pool_of_two_writes_the_same_files_as_one_process(sweep_reference, tmp_path):
    config = sweep_runs.write_config(tmp_path)
    assert _evaluate(tmp_path, config, "pool", "--workers", "2") == \
        sweep_reference.expected(tmp_path)
    assert not (tmp_path / "runs/sweep-units").exists()  # kept only until the run folder is written


def test_rows_come_in_the_canonical_order(tmp_path):
    """Per experiment: per seed, every policy in its order; then the best fixed angle.

    Only the experiment whose rows are checked runs (``--experiments``): the order is made per
    experiment, and the others' plots (the patrol's detection-curve fit) cost ~25 s."""
    config = sweep_runs.write_config(tmp_path)
    _evaluate(tmp_path, config, "one", "--workers", "1", "--experiments", "localization-lab")
    lines = (tmp_path / "one/episodes.csv").read_text().splitlines()[1:]
    rows = [line.split(",")[:3] for line in lines if line.startswith("localization-lab,")]
    policies = [policy for _, policy, _ in rows[:4]]
    assert len(set(policies)) == 4
    seeds = [str(s) for s in range(10_000, 10_000 + sweep_runs.SEEDS)]
    assert rows[:48] == [["localization-lab", p, s] for s in seeds for p in policies]
    assert rows[48:] == [["localization-lab", ORACLE_NAME, s] for s in seeds]


@pytest.mark.slow  # a sweep killed and run again: ~16 s on two cores
def test_a_killed_sweep_started_again_runs_only_the_rest_and_writes_the_same_files(
        sweep_reference, tmp_path):
    folder, expected = tmp_path, sweep_reference.expected(tmp_path)
    config = sweep_runs.write_config(folder)
    store = folder / "runs/sweep-units"
    cmd = [sys.executable, str(sweep_runs.ROOT / "evaluate.py"), str(config), "--workers", "1"]
    env = {**os.environ, "PYTHONPATH": str(sweep_runs.ROOT)}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while len(list(store.glob("*/*.unit"))) < 3 and proc.poll() is None \
            and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    kept = len(list(store.glob("*/*.unit")))
    assert proc.returncode == -signal.SIGKILL and kept >= 3
    assert not [p for p in (folder / "runs").iterdir() if not p.name.endswith("-units")]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    total = 2 * (4 + 3 + 2 + 3)  # two chunks per policy
    assert f"{kept}/{total}" in done.stderr  # the bar starts at the units kept
    assert sweep_runs.checksums(sweep_runs.take_run(folder, "resumed")) == expected


def _rows(config, executor=None, store=None):
    rows, _ = run(config, progress=False, executor=executor, store=store)
    return [r.row() for r in rows]


def _config(tmp_path):
    return validate_config(yaml.safe_load(sweep_runs.write_config(tmp_path).read_text()))


def test_a_unit_whose_worker_dies_is_retried_on_a_new_pool(tmp_path, monkeypatch, sweep_rows):
    config, expected = _config(tmp_path), sweep_rows
    marker = tmp_path / "died"
    real = sweep.units

    def dying_units(cfg, experiments):
        todo, describe = real(cfg, experiments)
        todo[5] = Unit(todo[5].key, sweep_units.die_once, (marker, todo[5].fn, *todo[5].args))
        return todo, describe

    monkeypatch.setattr(sweep, "units", dying_units)
    assert _rows(config, make_executor(workers=2)) == expected
    assert marker.exists()


def test_a_failed_unit_is_reported_and_a_rerun_finishes_with_the_same_rows(tmp_path, monkeypatch,
                                                                           sweep_rows):
    config, expected = _config(tmp_path), sweep_rows
    store, calls = UnitStore(tmp_path / "units"), tmp_path / "calls"
    real = sweep.units

    def failing_units(cfg, experiments):
        todo, describe = real(cfg, experiments)
        todo[2] = Unit(todo[2].key, sweep_units.fail, (2,))
        return todo, describe

    monkeypatch.setattr(sweep, "units", failing_units)
    with pytest.raises(sweep.UnitsFailedError) as failed:
        run(config, progress=False, executor=make_executor(workers=2, retries=1), store=store)
    assert failed.value.lines == ["unit 0-1-0 (experiment localization-lab, policy random, "
                                  "seeds 10000..10009) failed after 2 attempts: ValueError: "
                                  "unit 2 cannot be done"]
    total = len(list(store.folder.iterdir()))
    assert total == failed.value.total - 1

    def counted_units(cfg, experiments):
        todo, describe = real(cfg, experiments)
        return [Unit(u.key, sweep_units.count_calls, (calls, u.fn, *u.args)) for u in todo], \
            describe

    monkeypatch.setattr(sweep, "units", counted_units)
    assert _rows(config, make_executor(workers=1), store) == expected
    assert len(list(calls.iterdir())) == 1  # only the failed unit ran again


@pytest.mark.slow  # ~15 s: two full command runs (a failing one and its rerun)
def test_the_command_reports_failed_units_writes_nothing_and_a_rerun_finishes(
        sweep_reference, tmp_path, capsys, monkeypatch):
    folder, expected = tmp_path, sweep_reference.expected(tmp_path)
    config = sweep_runs.write_config(folder)
    real = sweep.units

    def failing_units(cfg, experiments):
        todo, describe = real(cfg, experiments)
        for k in (3, 7):
            todo[k] = Unit(todo[k].key, sweep_units.fail, (k,))
        return todo, describe

    monkeypatch.setattr(sweep, "units", failing_units)
    assert evaluate.main([str(config), "--no-progress", "--workers", "1"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("error: unit 0-1-1 (experiment localization-lab, policy random, "
                             "seeds 10010..10011) failed after 3 attempts: ValueError: unit 3")
    assert err[1].startswith("error: unit 0-3-1 (") and len(err) == 3
    assert err[2].startswith("note: ") and "units finished and are kept in" in err[2]
    assert [p.name for p in (folder / "runs").iterdir()] == ["sweep-units"]
    monkeypatch.setattr(sweep, "units", real)
    assert _evaluate(folder, config, "rerun", "--workers", "1") == expected


@pytest.mark.parametrize(
    ("flags", "block", "message"),
    [
        (["--workers", "0"], None, "error: --workers: expected an integer in [1, 1024], got 0"),
        (["--workers", "two"], None, "error: --workers: expected an integer in [1, 1024], got 'two'"),
        (["--executor", "dask"], None,
         "error: --executor: expected one of ('local', 'ray'), got 'dask'"),
        (["--address", "head:6379"], None,
         "error: --address: only for the ray executor (config.executor.kind: ray)"),
        ([], {"workers": 0}, "error: config.executor.workers: expected an integer in [1, 1024], got 0"),
        ([], {"kind": "ray", "nodes": 3}, "error: config.executor: unknown keys ['nodes']"),
    ],
)
def test_bad_executor_flags_and_keys_are_one_line_errors(tmp_path, capsys, flags, block,
                                                         message):
    config = sweep_runs.write_config(tmp_path)
    if block is not None:
        data = yaml.safe_load(config.read_text())
        config.write_text(yaml.safe_dump({**data, "executor": block}))
    assert evaluate.main([str(config), "--no-progress", *flags]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1
    assert not (tmp_path / "runs").exists()


@pytest.mark.slow  # the sweep again on another executor: ~16 s
def test_the_executor_key_does_not_change_the_episodes(sweep_reference, tmp_path):
    expected = sweep_reference.checksums
    config = sweep_runs.write_config(tmp_path)
    data = yaml.safe_load(config.read_text())
    config.write_text(yaml.safe_dump({**data, "executor": {"workers": 2, "retries": 0}}))
    assert evaluate.main([str(config), "--no-progress"]) == 0
    run_folder = sweep_runs.take_run(tmp_path, "keyed")
    assert sweep_runs.checksums(run_folder)["episodes.csv"] == expected["episodes.csv"]
    saved = yaml.safe_load((run_folder / "results.json").read_text())["config"]["executor"]
    assert saved == {"kind": "local", "workers": 2, "address": None, "retries": 0}


def test_ctrl_c_says_that_the_finished_units_are_kept(tmp_path, capsys, monkeypatch):
    import bounce_gym_experiments.runner

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(bounce_gym_experiments.runner, "run", interrupted)
    assert evaluate.main([str(sweep_runs.write_config(tmp_path)), "--workers", "1"]) == 130
    assert "the finished units are kept; run the same command again" in capsys.readouterr().err
