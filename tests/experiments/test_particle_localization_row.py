"""A localization row with the particle filter (issue 24, item 4) runs through evaluate.py with
its own policy and reports the claims' columns."""

import json
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402


def test_a_particle_localization_row_runs(tmp_path):
    row = {"name": "localization-particles-lab-kinematic",
           "env": "bounce_gym/BounceLocalization-v0",
           "env_kwargs": {"backend": "kinematic", "angles": [45, 135],
                          "task_kwargs": {"filter_factory": "particles", "particles": 500}},
           "seeds": [10_000, 10_001], "max_steps": 6, "horizon_reason": "a quick test",
           "policies": ["planner"]}
    config = {"name": "particles", "output": str(tmp_path / "runs"),
              "models": str(tmp_path / "m"), "experiments": [row]}
    path = tmp_path / "particles.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--workers", "1"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    summary = json.loads((folder / "results.json").read_text())["summary"]
    (planner,) = [s for s in summary if s["experiment"] == row["name"]]
    assert planner["policy"].startswith("particles")
    assert {"correct", "wrong_claim"} <= set(json.dumps(planner).replace('"', " ").split())
