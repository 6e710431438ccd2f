"""configs/benchmark.yaml: what it contains, that it validates, and that a tiny-budget run of it
writes the leaderboard (Markdown, CSV, plot) with intervals and counts in every cell."""

import csv
import re
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from bounce_gym import worlds
from bounce_gym.worlds import generators
from bounce_gym_experiments.config import configs_folder, load_config, validate_config
from bounce_gym_experiments.runner import prepare_experiment

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402

BENCHMARK = configs_folder() / "benchmark.yaml"
CELL = re.compile(r"-?\d+(\.\d+)? \[(-?\d+(\.\d+)?, -?\d+(\.\d+)?|-, -)\] n=\d+")


def test_the_benchmark_covers_every_task_with_200_held_out_episodes():
    config = validate_config(load_config(BENCHMARK))
    assert config["leaderboard"] is True
    experiments = config["experiments"]
    tasks = {(e["env"], e["env_kwargs"].get("world", "default")) for e in experiments}
    assert {env for env, _ in tasks} == {
        "bounce_gym/BounceNavigation-v0", "bounce_gym/BounceNavigation-v1",
        "bounce_gym/BounceLocalization-v0",
        "bounce_gym/BounceCoverage-v0", "bounce_gym/MultiBounceCoverage-v0",
        "bounce_gym/MultiBounceMonitoring-v0", "bounce_gym/Drifter-v0",
        "bounce_gym/MultiDrifter-v0", "bounce_gym/Patrol-v0"}
    navigation = [w for env, w in tasks if env == "bounce_gym/BounceNavigation-v0"]
    assert len(navigation) == 2 and any(w.endswith("bench_grid_14x22.yaml") for w in navigation)
    for exp in experiments:
        assert exp["difficulty"] in ("easy", "medium", "hard")
        assert exp["seeds"] == list(range(10_000, 10_200))
        assert "horizon_reason" not in exp  # every task at its registered horizon
        if exp["env"] == "bounce_gym/MultiDrifter-v0":  # deployments: all the family runs
            assert exp["policies"] == ["planner", "random"]
        elif exp["env"] == "bounce_gym/Patrol-v0":  # patrollers (no fixed angle) vs the Stackelberg
            assert exp["policies"] == ["planner", "random", "rl"]  # best response
            assert exp["adversaries"] == ["best_response"]
        elif _physics(exp):  # no fixed angles on physics; agents where some were trained there
            assert exp["policies"][:2] == ["planner", "random"] and "fixed" not in exp["policies"]
        else:
            assert "rl" in exp["policies"] and "fixed" in exp["policies"]
    physics = [e["name"] for e in experiments if _physics(e)]
    assert physics == [e["name"] for e in experiments[:len(physics)]]  # they come first
    assert {"navigation-lab-dynamic-noise", "navigation-lab-v1-dynamic-noise",
            "localization-lab-dynamic-noise"} <= {e["name"] for e in experiments
                                                  if _physics(e) and "rl" in e["policies"]}


def test_the_generated_map_is_what_its_description_says():
    path = configs_folder() / "maps" / "bench_grid_14x22.yaml"
    world = worlds.load(path)
    again = generators.random_grid(np.random.default_rng(3), 14, 22, 14, 3,
                                   name="bench_grid_14x22")
    assert world == again and "default_rng(3)" in yaml.safe_load(path.read_text())["description"]


def _physics(exp: dict) -> bool:
    """Whether an experiment runs on pymunk's dynamic physics (its planners read tabulated bump
    maps, built once per map: minutes in a fresh home folder)."""
    return exp.get("env_kwargs", {}).get("physics") == "dynamic"


def _tiny(config: dict, tmp_path: Path, models: Path | None = None) -> Path:
    """``config`` with 2 seeds per experiment and its models from ``models`` (None: an empty
    folder), written under ``tmp_path``."""
    for exp in config["experiments"]:
        exp["seeds"] = {"start": 10_000, "count": 2}
        world = exp.get("env_kwargs", {}).get("world", "")
        if world.endswith(".yaml"):  # the copy lives elsewhere: point at the shipped map
            exp["env_kwargs"]["world"] = str(BENCHMARK.parent / world)
    config.update(output=str(tmp_path / "runs"), models=str(models or tmp_path / "models"))
    path = tmp_path / "bench.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    return path


@pytest.mark.long
def test_a_tiny_budget_benchmark_run_writes_the_leaderboard(tmp_path, capsys):
    """Every experiment but the physics ones (a slow test runs those)."""
    config = yaml.safe_load(BENCHMARK.read_text(encoding="utf-8"))
    config["experiments"] = [exp for exp in config["experiments"] if not _physics(exp)]
    path = _tiny(config, tmp_path)
    assert evaluate.main([str(path), "--no-progress"]) == 0
    capsys.readouterr()
    (folder,) = (tmp_path / "runs").iterdir()
    board = (folder / "leaderboard.md").read_text(encoding="utf-8")
    assert board.startswith("# benchmark: leaderboard")
    assert "on lab_navigation;" in board and "on bench_grid_14x22.yaml;" in board
    assert "on scb_like;" in board and "on two_sink;" in board
    for exp in config["experiments"]:
        assert f"## {exp['name']} ({exp['difficulty']})" in board
    head, tables = board.split("\n## Who wins\n")[1].split("\n## ", 1)
    verdicts = [line for line in head.splitlines() if line.startswith("| ")][1:]
    shown = [line.split(" | ")[0][2:] for line in verdicts]
    left_out = re.search(r"on the score: (.*)\.", head)
    left_out = left_out[1].split(", ") if left_out else []
    # with two seeds hardly anything is apart; every experiment is in the table or named
    assert sorted(shown + left_out) == sorted(e["name"] for e in config["experiments"])
    with (folder / "verdicts.csv").open(encoding="utf-8") as fh:
        assert [v["experiment"] for v in csv.DictReader(fh)] == [
            e["name"] for e in config["experiments"]]
    rows = [line for line in tables.splitlines() if line.startswith("| ")
            and "policy" not in line]
    assert len(rows) >= 6 * 3 and all(CELL.search(line) for line in rows)
    # no models in this run: every rl folder is named in the notes, no rl row is shown
    assert "## Notes" in board and "navigation-lab-privileged" in board
    assert "| rl " not in board
    with (folder / "leaderboard.csv").open(encoding="utf-8") as fh:
        lines = list(csv.DictReader(fh))
    assert {line["experiment"] for line in lines} == {e["name"] for e in config["experiments"]}
    assert {"difficulty", "score", "success_lo", "success_hi", "success_n"} <= set(lines[0])
    navigation = [line for line in lines if line["experiment"] == "navigation-lab"]
    scores = [float(line["success"]) for line in navigation]
    assert scores == sorted(scores, reverse=True)  # best first
    assert (folder / "leaderboard.png").stat().st_size > 1000


def test_every_policy_of_a_benchmark_experiment_starts_from_the_same_draw():
    """Policies compared in one row start from the same draw (issue 34): no policy picks its own
    start unless the experiment imposes one start on all of them (monitoring's cycle start);
    the drifter deployments, whose policies are starts, are the one exception. (A patrol
    policy's options also announce its strategy to the env, ``strategy``: not a start.)"""
    config = validate_config(load_config(BENCHMARK))
    for exp in config["experiments"]:
        if exp["env"] == "bounce_gym/MultiDrifter-v0":
            continue
        exp = {**exp, "policies": [k for k in exp["policies"] if k != "rl"]}
        prepared = prepare_experiment(exp, ROOT / "no-models", exp["name"])
        for seed in (10_000, 10_001):
            for entrant in prepared.entrants:
                episode = prepared.family.episode(entrant.env, entrant.policy, entrant.setup)
                own = entrant.policy.start_options(entrant.env, seed)
                if exp["env"] == "bounce_gym/Patrol-v0":
                    own = {k: v for k, v in (own or {}).items() if k != "strategy"} or None
                imposed = episode.start_options(seed)
                assert own is None or own == imposed, (exp["name"], entrant.policy.name)
        names = [e.policy.name for e in prepared.entrants]
        if exp["name"] == "multirobot-monitoring-15x15-cycle-start":
            assert "planner (cycle start)" in names
        if exp["name"] == "multirobot-coverage-10x10":
            assert "planner (start observed)" in names


@pytest.mark.slow
@pytest.mark.long  # the three worlds' bump tables are built here: ~3.5 min of the ~5
def test_the_physics_experiments_run_with_their_agents(tmp_path, capsys):
    """The physics experiments, 2 seeds each, with the shipped agents: every row is there, the
    agents of both tracks are named by what they observe, and the planners predict."""
    config = yaml.safe_load(BENCHMARK.read_text(encoding="utf-8"))
    config["experiments"] = [exp for exp in config["experiments"] if _physics(exp)]
    assert config["experiments"][0] == next(e for e in yaml.safe_load(
        BENCHMARK.read_text(encoding="utf-8"))["experiments"])  # the physics rows come first
    path = _tiny(config, tmp_path, ROOT / "baselines" / "agents")
    assert evaluate.main([str(path), "--no-progress", "--tables"]) == 0
    out = capsys.readouterr().out
    for name in ("search planner", "continuous-angle planner", "roadmap planner (pose observed)",
                 "rl dqn (pose observed)", "rl recurrentppo", "particles (expected entropy)"):
        assert name in out, name
