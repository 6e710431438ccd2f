"""The rows of configs/eval_localization.yaml (issue 24, item 4) run through evaluate.py, the
particle filter's with its own policy, and report the claims' columns."""

import json
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402


def test_the_localization_config_runs(tmp_path):
    """Every row of the documented config, with two seeds, a short horizon and few particles."""
    config = yaml.safe_load((ROOT / "configs" / "eval_localization.yaml").read_text())
    for row in config["experiments"]:
        row.update(seeds=[10_000, 10_001], max_steps=6, horizon_reason="a quick test")
        task = row["env_kwargs"].get("task_kwargs", {})
        if task.get("filter_factory") == "particles":  # few on the dynamic physics (slow)
            dynamic = row["env_kwargs"].get("physics") == "dynamic"
            task["particles"] = 40 if dynamic else 500
    config.update(output=str(tmp_path / "runs"), models=str(tmp_path / "m"))
    path = tmp_path / "localization.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--workers", "1"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    summary = json.loads((folder / "results.json").read_text())["summary"]
    for row in config["experiments"]:
        ran = {s["policy"]: s for s in summary if s["experiment"] == row["name"]}
        assert ran, row["name"]
        for result in ran.values():
            assert {"correct", "wrong_claim"} <= set(result), result
        if "particles" in row["name"]:
            assert all(policy.startswith("particles") for policy in ran)
