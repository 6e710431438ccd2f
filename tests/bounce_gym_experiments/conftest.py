"""The experiments tests' helper modules on ``sys.path``, and this checkout with them on
``PYTHONPATH``, so that the worker processes of a sweep — a pool process, a Ray worker — import
the helpers by name and this checkout's package (not another install of it); and the sweep
tests' shared references: the small evaluation in one process (`sweep_reference`, once per test
run) and its rows (`sweep_rows`, once per worker)."""

import os
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
_paths = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
os.environ["PYTHONPATH"] = os.pathsep.join(
    [str(HERE), str(ROOT), *(p for p in _paths if p not in (str(HERE), str(ROOT)))])


class SweepReference:
    """The small evaluation of `sweep_runs` run once in one process (``evaluate.py
    --workers 1``) in ``folder``: ``checksums`` of its episodes.csv and results.json.

    A run elsewhere writes the same episodes.csv; its results.json differs only where it
    records the folder it was configured with (``output``, ``models``, a note naming the models
    folder), so `expected` gives the checksums a run configured in another folder
    (``sweep_runs.write_config(other)``) must have: results.json with this folder's path
    replaced by the other's, compared byte for byte."""

    def __init__(self, folder: Path, checksums: dict[str, str]) -> None:
        self.folder, self.checksums = folder, checksums

    def expected(self, folder: Path) -> dict[str, str]:
        import hashlib

        results = (self.folder / "one/results.json").read_bytes()
        results = results.replace(str(self.folder).encode(), str(folder).encode())
        return {"episodes.csv": self.checksums["episodes.csv"],
                "results.json": hashlib.sha256(results).hexdigest()}


@pytest.fixture(scope="session")
def sweep_reference(tmp_path_factory) -> SweepReference:
    """The one-process reference of the sweep tests (test_sweep.py, test_ray_executor.py), made
    once per test run: a whole evaluation, ~30 s of CPU (most of it the patrol experiment's
    detection-curve fit for its plots), so it is made by the first test that asks, in the run's
    folder (tests/conftest.py, ``$BOUNCE_GYM_TEST_RUN``) under a lock, and read back by every
    other test and pytest-xdist worker. Tests never write into its folder: each runs its own
    evaluation in its ``tmp_path`` and compares with `SweepReference.expected`."""
    import json

    import sweep_runs

    from bounce_gym.files import atomic_write, locked

    run = os.environ.get("BOUNCE_GYM_TEST_RUN")  # tests/conftest.py's RUN_VARIABLE
    folder = (Path(run) if run else tmp_path_factory.getbasetemp()) / "sweep-reference"
    done = folder / "checksums.json"
    with locked(done):
        if not done.is_file():
            if str(ROOT) not in sys.path:
                sys.path.insert(0, str(ROOT))
            import evaluate

            config = sweep_runs.write_config(folder)
            assert evaluate.main([str(config), "--no-progress", "--workers", "1"]) == 0
            checksums = sweep_runs.checksums(sweep_runs.take_run(folder, "one"))
            atomic_write(done, json.dumps(checksums).encode())
    return SweepReference(folder, json.loads(done.read_text()))


@pytest.fixture(scope="session")
def sweep_rows(tmp_path_factory) -> list[dict]:
    """The rows of the small evaluation run in this process (``runner.run`` with its default
    executor), made once per pytest-xdist worker for the tests that run it on another executor
    or with failures and compare rows (rows do not depend on the folder the configuration
    names). Compare with it; do not change it."""
    import sweep_runs
    import yaml

    from bounce_gym_experiments.config import validate_config
    from bounce_gym_experiments.runner import run

    folder = tmp_path_factory.mktemp("sweep-rows")
    config = validate_config(yaml.safe_load(sweep_runs.write_config(folder).read_text()))
    return [r.row() for r in run(config, progress=False)[0]]
