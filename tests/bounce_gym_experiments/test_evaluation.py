"""evaluate.py and train.py: configurations, outputs, and the RL round trip."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from baselines.rl.train import validate_train_config
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.config import load_config, validate_config
from bounce_gym_experiments.report import summarise, table_rows
from bounce_gym_experiments.runner import run

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402
import train  # noqa: E402


def _experiment(name: str) -> dict:
    return next(e for e in load_config()["experiments"] if e["name"] == name)


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ([], "expected a mapping"),
        ({"experiments": [], "colour": "red"}, "unknown keys \\['colour'\\]"),
        ({"name": "x"}, "missing key 'experiments'"),
        ({"experiments": []}, "at least one experiment"),
        ({"experiments": [{"name": "a"}]}, "missing key 'env'"),
        ({"experiments": [{"name": "a", "env": "bounce_gym/Nope-v0"}]}, "unknown environment"),
        ({"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0", "seeds": [0.5]}]},
         "seeds"),
        ({"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0", "seeds": [9_999]}]},
         r"config.experiments\[0\].seeds: evaluation seeds must not overlap the tuning seeds"),
        ({"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0", "policies": ["oracle"]}]},
         "policies"),
        ({"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0", "max_steps": "10"}]},
         "max_steps: expected int"),
        ({"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0"},
                          {"name": "a", "env": "bounce_gym/Bounce-v0"}]}, "used twice"),
    ],
)
def test_bad_evaluation_configs_raise(config, message):
    with pytest.raises(ConfigError, match=message):
        validate_config(config)


def test_the_default_config_is_the_shipped_yaml():
    assert load_config() == yaml.safe_load((ROOT / "configs/eval_default.yaml").read_text())
    assert validate_config(load_config())["name"] == "default"


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "a2c", "total_timesteps": 10},
         "algo"),
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "ppo"}, "total_timesteps"),
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "ppo", "total_timesteps": 10,
          "lr": 1}, "unknown keys"),
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "ppo", "total_timesteps": True},
         "total_timesteps: expected int"),
    ],
)
def test_bad_training_configs_raise(config, message):
    with pytest.raises(ConfigError, match=message):
        validate_train_config(config)


def test_evaluate_cli_writes_table_csv_json_and_plots(tmp_path, capsys):
    config = {"name": "loc", "output": str(tmp_path / "runs"), "experiments": [
        dict(_experiment("localization-lab"), seeds=[10_000, 10_001])]}
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress",
                          "--tables"]) == 0
    out = capsys.readouterr().out
    assert "planner (angle switching)" in out and "fixed 45°" in out
    (folder,) = (tmp_path / "runs").iterdir()
    results = json.loads((folder / "results.json").read_text())
    # planner, random, two fixed angles, and the best fixed angle in hindsight (derived rows)
    assert len(results["episodes"]) == 2 * 5
    assert (folder / "episodes.csv").read_text().count("\n") == 1 + 10
    assert list(folder.glob("*.png"))
    assert evaluate.main([str(tmp_path / "missing.yaml")]) == 2


def test_rl_smoke_train_then_evaluate_scores_the_model(tmp_path):
    """Issue 5: a short PPO run on a small navigation world produces a model that evaluate.py
    loads and scores."""
    env_kwargs = {"world": "square", "backend": "cell", "angles": [90, 135]}
    train_config = {"name": "nav-small", "env": "bounce_gym/BounceNavigation-v0",
                    "env_kwargs": env_kwargs, "algo": "ppo", "total_timesteps": 512,
                    "n_envs": 2, "hyperparams": {"n_steps": 128},
                    "models": str(tmp_path / "models")}
    assert train.main([str(_write(tmp_path / "t.yaml", train_config)), "--no-progress"]) == 0
    assert (tmp_path / "models/nav-small/ppo_seed0.zip").is_file()
    config = {"name": "smoke", "output": str(tmp_path / "runs"), "models": str(tmp_path / "models"),
              "experiments": [{"name": "nav-small", "env": "bounce_gym/BounceNavigation-v0",
                               "env_kwargs": env_kwargs, "seeds": [10_000, 10_001],
                               "max_steps": 30, "horizon_reason": "a quick test",
                               "policies": ["rl", "random"]}]}
    rows, _ = run(config, progress=False)
    scored = [r for r in rows if r.policy.startswith("rl ")]
    # the model plays sampled and greedy, each seed (sweep order: by seed, then by policy)
    assert [(r.seed, r.policy, r.group) for r in scored] == [
        (seed, f"rl ppo_seed0{suffix}", f"rl ppo{suffix}")
        for seed in (10_000, 10_001) for suffix in ("", " (greedy)")]
    assert all(r.steps >= 1 for r in scored)
    summary = summarise(rows)
    assert all("success" in s for s in summary)
    table, per_seed = table_rows(rows)
    assert [t["policy"] for t in table] == ["random", "rl ppo", "rl ppo (greedy)"]
    assert [s["policy"] for s in per_seed] == ["rl ppo_seed0", "rl ppo_seed0 (greedy)"]


def test_visibility_scenario_runs_the_safe_plan(tmp_path):
    """Issue 6: the two_rooms plan e0→e16 as a policy in BounceEnv(fixed rule) reaches segment 16
    in every episode; random angles do not; plots of P', G_safe and the plan's cone are written."""
    config = {"name": "vis", "output": str(tmp_path / "runs"), "experiments": [
        dict(_experiment("visibility-two-rooms"), seeds={"start": 10_000, "count": 5})]}
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    summary = {s["policy"]: s for s in json.loads((folder / "results.json").read_text())["summary"]}
    assert summary["safe plan (fewest)"]["success"] == 1.0
    assert summary["random"]["success"] < 1.0
    for plot in ("partition", "safe-graph", "plan"):
        assert (folder / f"visibility-two-rooms-{plot}.png").stat().st_size > 1000


def test_patrol_scenario_converges_to_the_limit_cycle(tmp_path):
    """Issue 6: patrolling the heptagon's edges with the fixed rule at θ = 0.1 (Def. 15,
    C(F) = 5.0864e-6, Nilles et al. 2021, Theorem 1) — the robot ends on the predicted limit cycle;
    random angles do not; the limit cycle is plotted."""
    config = {"name": "patrol", "output": str(tmp_path / "runs"), "experiments": [
        dict(_experiment("visibility-patrol-heptagon"), seeds=[10_000, 10_001, 10_002])]}
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    summary = {s["policy"]: s for s in json.loads((folder / "results.json").read_text())["summary"]}
    assert summary["patrol cycle (C(F) = 5.1e-06)"]["success"] == 1.0
    assert summary["random"]["success"] == 0.0
    assert (folder / "visibility-patrol-heptagon-limit-cycle.png").stat().st_size > 1000


@pytest.mark.parametrize(("block", "message"), [
    ({"start": 0, "goal": 99}, "visibility.goal"),
    ({"start": 0, "goal": 16, "patrol": [3, 4]}, "exactly one of"),
    ({"start": 0, "patrol": "all"}, "visibility.patrol"),
    ({"start": 0, "goal": 16, "plan": "shortest"}, "visibility.plan"),
    ({"start": 0, "goal": 16, "colour": 1}, "unknown keys"),
    ({"start": 7, "goal": 14}, "no safe fewest plan"),
])
def test_bad_visibility_blocks_raise(block, message):
    exp = dict(_experiment("visibility-two-rooms"), visibility=block, seeds=[10_000])
    with pytest.raises(ConfigError, match=message):
        run({"experiments": [exp]}, progress=False)


def _tiny_config(tmp_path: Path) -> Path:
    config = {"name": "tiny", "output": str(tmp_path / "runs"), "experiments": [
        dict(_experiment("localization-lab"), seeds=[10_000], policies=["random"], max_steps=20,
             horizon_reason="a quick test")]}
    return _write(tmp_path / "tiny.yaml", config)


@pytest.mark.parametrize("command", [["evaluate.py"], ["-m", "bounce_gym_experiments.cli", "evaluate"]])
def test_evaluate_commands_run_a_config_and_report_bad_ones(tmp_path, command):
    """`python evaluate.py` and `bounce-gym evaluate` (here `python -m bounce_gym_experiments.cli`): the
    same run folder, and a bad configuration is one ``error:`` line with status 2."""
    run_it = [sys.executable, *[str(ROOT / c) if c.endswith(".py") else c for c in command]]
    done = subprocess.run([*run_it, str(_tiny_config(tmp_path)), "--no-progress"], cwd=ROOT,
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    # who wins, in 100 columns (the report's path aside), and every table in tables.txt
    summary = done.stdout.split("\nWho wins: ")[1]
    assert "localization-lab: steps_to_correct (lower is better); winner: " in summary
    assert max(len(line) for line in summary.splitlines() if str(tmp_path) not in line) <= 100
    (folder,) = (tmp_path / "runs").iterdir()
    assert f"table: {folder}/tables.txt" in summary
    assert "localization-lab  random" in (folder / "tables.txt").read_text()
    assert (folder / "episodes.csv").read_text().count("\n") == 2
    bad = subprocess.run([*run_it, str(tmp_path / "missing.yaml")], cwd=ROOT,
                         capture_output=True, text=True, check=False)
    assert bad.returncode == 2
    assert bad.stderr.splitlines() == [f"error: config: file '{tmp_path / 'missing.yaml'}' "
                                       "does not exist"]


def test_train_command_reports_a_bad_config(tmp_path):
    bad = subprocess.run([sys.executable, "-m", "bounce_gym_experiments.cli", "train",
                          str(_write(tmp_path / "t.yaml", {"name": "x"}))], cwd=ROOT,
                         capture_output=True, text=True, check=False)
    assert bad.returncode == 2 and bad.stderr.startswith("error: config: missing key")
