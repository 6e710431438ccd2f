"""The evaluation configs' rows on the pymunk backend's dynamic physics (issue 23): each stands
next to the same task on the kinematic or cell backend, differing only in the motion model, and
every one of them runs through evaluate.py (two seeds, a short horizon)."""

import json
import sys
from pathlib import Path

import pytest
import yaml

from experiments.config import load_config, validate_config

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402

CONFIGS = ["eval_default.yaml", "eval_multirobot.yaml", "eval_physics.yaml"]
DYNAMIC = {"backend": "pymunk", "physics": "dynamic"}
#: what may differ between a row and its dynamic sibling: the motion model, the cell model's
#: diagonal rule (cell rows) and the disk radius (point robots exist only on the exact models)
MODEL_KEYS = {"backend", "physics", "corner_rule", "robot_radius"}


def _experiments(name: str) -> list[dict]:
    return load_config(ROOT / "configs" / name)["experiments"]


def _dynamic(exp: dict) -> bool:
    return all(exp["env_kwargs"].get(k) == v for k, v in DYNAMIC.items())


def _rest(exp: dict) -> tuple:
    """The task: env, its options but the motion model, and the planner's arguments (seeds,
    horizons and policies may differ: dynamic rows run fewer episodes in the quick configs)."""
    kwargs = {k: v for k, v in exp["env_kwargs"].items() if k not in MODEL_KEYS}
    return exp["env"], kwargs, exp.get("planner_kwargs")


@pytest.mark.parametrize("name", CONFIGS)
def test_every_dynamic_row_has_a_kinematic_or_cell_sibling(name):
    experiments = _experiments(name)
    validate_config({"experiments": experiments})
    dynamic = [e for e in experiments if _dynamic(e)]
    assert dynamic, f"{name} has no row on dynamic physics"
    for exp in dynamic:
        assert exp["name"].endswith("-pymunk-dynamic")
        stem = exp["name"].removesuffix("-pymunk-dynamic")
        siblings = [e for e in experiments if e["name"] in (stem, f"{stem}-kinematic",
                                                             f"{stem}-cell")]
        assert siblings, f"{exp['name']}: no kinematic or cell row"
        for sibling in siblings:
            assert sibling["env_kwargs"].get("backend", "kinematic") in ("kinematic", "cell")
            assert _rest(sibling) == _rest(exp), f"{exp['name']} vs {sibling['name']}"


def test_the_physics_comparison_has_every_backend_per_task():
    names = {e["name"] for e in _experiments("eval_physics.yaml")}
    stems = {n.rsplit("-", 1)[0].removesuffix("-pymunk") for n in names}
    for stem in stems:
        assert {f"{stem}-cell", f"{stem}-kinematic", f"{stem}-pymunk-ideal",
                f"{stem}-pymunk-dynamic"} <= names, stem


def test_every_dynamic_row_runs(tmp_path):
    rows = []
    for name in CONFIGS:
        for exp in _experiments(name):
            if _dynamic(exp) and exp["name"] not in {r["name"] for r in rows}:
                rows.append(dict(exp, seeds=[10_000, 10_001], max_steps=12,
                                 horizon_reason="a quick test", rl_models=[]))
    for row in rows:
        row.pop("rl_models")
    config = {"name": "dyn", "output": str(tmp_path / "runs"), "models": str(tmp_path / "m"),
              "experiments": rows}
    path = tmp_path / "dyn.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--workers", "1"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    summary = json.loads((folder / "results.json").read_text())["summary"]
    done = {(s["experiment"], s["policy"]) for s in summary}
    for row in rows:
        ran = {policy for experiment, policy in done if experiment == row["name"]}
        assert len(ran) >= 2, f"{row['name']}: {ran}"  # the planner and random bouncing
