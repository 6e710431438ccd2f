"""The Ray executor on a local instance of two CPUs (started once for this module, no
dashboard, shut down after): units, an exception retried, a worker killed and retried by Ray,
a unit failing for good, the small evaluation giving the same files as in one process, and a
sweep interrupted by a failing unit and started again (the one-process references: conftest.py's
``sweep_reference`` and ``sweep_rows``, shared with test_sweep.py)."""

import pytest
import sweep_runs
import sweep_units
import yaml

from bounce_gym_experiments import sweep
from bounce_gym_experiments.config import validate_config
from bounce_gym_experiments.executors import (
    RayExecutor,
    Unit,
    UnitFailure,
    UnitStore,
    make_executor,
)
from bounce_gym_experiments.runner import run

ray = pytest.importorskip("ray")


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RAY_USAGE_STATS_ENABLED", "0")
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
        yield
        ray.shutdown()


def _squares(n):
    return [Unit(f"sq{k}", sweep_units.square, (k,)) for k in range(n)]


def test_units_run_as_ray_tasks_and_are_stored(tmp_path):
    executor = make_executor("ray", workers=2)
    assert isinstance(executor, RayExecutor)
    store = UnitStore(tmp_path)
    results, failures = executor.run(_squares(5), store, progress=False)
    assert results == {f"sq{k}": k * k for k in range(5)} and failures == []
    assert store.load("sq4") == 16


def test_a_killed_worker_is_retried_by_ray_and_an_exception_here(tmp_path):
    units = [*_squares(3),
             Unit("died", sweep_units.die_once, (tmp_path / "d", sweep_units.square, 5)),
             Unit("raised", sweep_units.raise_once, (tmp_path / "r", sweep_units.square, 6))]
    results, failures = make_executor("ray", workers=2, retries=1).run(
        units, UnitStore(tmp_path / "units"), progress=False)
    assert failures == [] and results["died"] == 25 and results["raised"] == 36


def test_units_failing_for_good_are_reported_while_the_others_complete(tmp_path):
    units = [Unit("dead", sweep_units.die, (1,)), *_squares(3), Unit("bad", sweep_units.fail,
                                                                     (2,))]
    results, failures = make_executor("ray", workers=2, retries=1).run(
        units, UnitStore(tmp_path / "units"), progress=False)
    assert results == {f"sq{k}": k * k for k in range(3)}
    assert failures == [UnitFailure("dead", "worker died", 2),
                        UnitFailure("bad", "ValueError: unit 2 cannot be done", 2)]


@pytest.mark.long
@pytest.mark.slow  # a whole evaluation on Ray (and the one-process reference if no test made it
# yet): ~30-60 s on two cores (the executors benchmark's test compares the same three executors
# on a smaller evaluation)
def test_the_evaluation_on_ray_writes_the_same_files_as_one_process(sweep_reference, tmp_path):
    import evaluate

    config = sweep_runs.write_config(tmp_path)
    expected = sweep_reference.expected(tmp_path)
    assert evaluate.main([str(config), "--no-progress", "--executor", "ray", "--workers",
                          "2"]) == 0
    assert sweep_runs.checksums(sweep_runs.take_run(tmp_path, "ray")) == expected


def test_an_interrupted_sweep_on_ray_resumes_with_only_the_rest(tmp_path, monkeypatch, sweep_rows):
    config = validate_config(yaml.safe_load(sweep_runs.write_config(tmp_path).read_text()))
    expected = sweep_rows
    store, calls, marker = UnitStore(tmp_path / "units"), tmp_path / "calls", tmp_path / "died"
    real = sweep.units

    def interrupted(cfg, experiments):  # one unit fails for good; another's worker dies once
        todo, describe = real(cfg, experiments)
        todo[4] = Unit(todo[4].key, sweep_units.fail, (4,))
        todo[9] = Unit(todo[9].key, sweep_units.die_once, (marker, todo[9].fn, *todo[9].args))
        return todo, describe

    monkeypatch.setattr(sweep, "units", interrupted)
    with pytest.raises(sweep.UnitsFailedError) as failed:
        run(config, progress=False, executor=make_executor("ray", workers=2, retries=1),
            store=store)
    assert [f.key for f in failed.value.failures] == ["0-2-0"] and marker.exists()

    def counted(cfg, experiments):
        todo, describe = real(cfg, experiments)
        return [Unit(u.key, sweep_units.count_calls, (calls, u.fn, *u.args)) for u in todo], \
            describe

    monkeypatch.setattr(sweep, "units", counted)
    rows, _ = run(config, progress=False, executor=make_executor("ray", workers=2), store=store)
    assert [r.row() for r in rows] == expected
    assert len(list(calls.iterdir())) == 1
