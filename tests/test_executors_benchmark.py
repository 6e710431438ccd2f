"""The executors benchmark (issue #17) on a tiny evaluation: a row per executor, identical
files."""

import importlib.util

import yaml

from benchmarks import executors
from experiments.config import load_config


def test_executors_benchmark_runs_and_finds_identical_files(tmp_path, capsys):
    experiment = next(e for e in load_config()["experiments"] if e["name"] == "localization-lab")
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump({"name": "tiny", "experiments": [experiment]}))
    out = executors.main(["--config", str(config), "--seeds", "2"])
    rows = out[str(config)]
    text = capsys.readouterr().out
    ray = importlib.util.find_spec("ray") is not None
    assert list(rows) == list(executors.EXECUTORS)[:3 if ray else 2]
    assert all(r["seconds"] > 0 for r in rows.values())
    assert len({(r["episodes.csv"], r["results.json"]) for r in rows.values()}) == 1
    assert "identical files for every executor" in text and "load average" in text
    assert ray or "ray (local, 2 CPUs): skipped" in text
