"""The bump tables that ship with the package (`bounce_gym.dynamics.bump_table.SHIPPED_TABLES`):
a cold run of the default evaluation's dynamic-physics experiments builds none, and each shipped
table predicts the simulator it tabulates."""

from __future__ import annotations

import zipfile

import pytest

from bounce_gym.dynamics.bump_table import (
    DEFAULT_HEADINGS,
    DEFAULT_SPACING,
    SHIPPED_TABLES,
    bump_table,
    table_fingerprint,
)
from bounce_gym.dynamics.table_check import table_error
from bounce_gym.model_cache import CACHE_VARIABLE
from bounce_gym_experiments.config import configs_folder, load_config, validate_config
from bounce_gym_experiments.runner import make_experiment_env, run
from bounce_gym_experiments.shipped_tables import SHIPPED_FOR, one_seed

SHIPPED = sorted(SHIPPED_TABLES.glob("*.npz"))


def _dynamic_experiments(name: str) -> list[dict]:
    config = validate_config(load_config(configs_folder() / name))
    return [exp for exp in config["experiments"]
            if exp["env_kwargs"].get("physics") == "dynamic"]


@pytest.mark.parametrize("name", SHIPPED_FOR)
def test_a_cold_run_of_the_shipped_evaluations_builds_no_table(name, tmp_path, monkeypatch):
    """Their planners on dynamic physics, one seed each, with an empty cache folder: every table
    they ask for is the package's, so none is written into the cache. (After a change to the
    physics: `python -m bounce_gym_experiments.shipped_tables` rewrites them.)"""
    monkeypatch.setenv(CACHE_VARIABLE, str(tmp_path))
    experiments = [{**exp, "policies": ["planner"]} for exp in _dynamic_experiments(name)]
    assert experiments
    config = validate_config({"name": "cold", "output": str(tmp_path / "runs"),
                              "experiments": experiments})
    rows, _ = run(one_seed(config), progress=False)
    assert {row.experiment for row in rows} == {exp["name"] for exp in experiments}
    assert not list(tmp_path.glob("bump_tables/*.npz"))


def test_the_shipped_tables_are_compressed_and_small():
    assert SHIPPED
    for path in SHIPPED:
        with zipfile.ZipFile(path) as npz:
            assert {item.compress_type for item in npz.infolist()} == {zipfile.ZIP_DEFLATED}
        assert path.stat().st_size < 2 * 2**20


def test_each_shipped_table_predicts_the_simulator_on_held_out_poses(tmp_path, monkeypatch):
    """The same bounds as tests/dynamics/test_bump_table.py's coarse table, on each shipped
    table (the default resolution, finer than that test's), found by the experiment of a
    shipped evaluation it serves."""
    monkeypatch.setenv(CACHE_VARIABLE, str(tmp_path))
    checked = set()
    for exp in (exp for name in SHIPPED_FOR for exp in _dynamic_experiments(name)):
        env = make_experiment_env(exp)
        try:
            dynamics = dict(env.unwrapped.options.robot_dynamics, noise=None)
            model = env.unwrapped.cell_model()
        finally:
            env.close()
        key = table_fingerprint(dynamics, DEFAULT_SPACING, DEFAULT_HEADINGS)
        if key not in {path.stem for path in SHIPPED} or key in checked:
            continue
        checked.add(key)
        report = table_error(bump_table(dynamics), model, dynamics, n=60, seed=3)
        assert not list(tmp_path.glob("bump_tables/*.npz"))  # the shipped table was read
        bumps, reset = report["bumps"], report["reset"]
        assert bumps["n"] >= 40 and reset["n"] >= 50
        assert bumps["same_state"]["share"] >= 0.85 and reset["same_state"]["share"] >= 0.85
        assert bumps["ticks_within_1"]["share"] >= 0.95
    assert checked == {path.stem for path in SHIPPED}  # none ships for nothing
