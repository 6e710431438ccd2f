"""Reports with research-grade statistics: every cell with its 95% interval and count, navigation
feasibility, the hindsight oracle, trained agents aggregated over training seeds, and the
provenance in results.json."""

import csv
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from bounce_gym.provenance import PACKAGES, git_state, provenance
from bounce_gym_experiments import stats
from bounce_gym_experiments.families import navigation
from bounce_gym_experiments.oracle import ORACLE_NAME, best_fixed_in_hindsight
from bounce_gym_experiments.report import estimate_text, format_table, summarise, table_rows
from bounce_gym_experiments.runner import EpisodeResult, run

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402
import train  # noqa: E402

NAV = "bounce_gym/BounceNavigation-v0"
SQUARE = {"world": "square", "backend": "cell", "angles": [90, 135]}
CELL = re.compile(r"-?\d+(\.\d+)? \[(-?\d+(\.\d+)?, -?\d+(\.\d+)?|-, -)\] n=\d+")


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def _square(**extra) -> dict:
    return {"name": "nav", "env": NAV, "env_kwargs": SQUARE,
            "seeds": {"start": 10_000, "count": 12}, "policies": ["planner", "random", "fixed"],
            **extra}


def test_cells_read_value_interval_and_count():
    assert estimate_text(0.515, 0.4461, 0.5833, 200) == "0.515 [0.446, 0.583] n=200"
    assert estimate_text(23.0, None, None, 1) == "23.0 [-, -] n=1"
    assert estimate_text(-5530.2, -6012.0, -5011.4, 20) == "-5530 [-6012, -5011] n=20"


def test_feasibility_on_a_tiny_navigation_config():
    rows, plots = run({"experiments": [_square()]}, progress=False)
    by_seed: dict[int, set] = {}
    for r in rows:
        by_seed.setdefault(r.seed, set()).add(r.metrics["feasible"])
        # on the cell backend the roadmap is the env's exact model: no policy reaches a goal
        # the model cannot reach, and success on the feasible episodes is success itself
        assert r.metrics["feasible"] or not r.metrics["success"]
        assert ("success_feasible" in r.metrics) == r.metrics["feasible"]
    assert all(len(values) == 1 for values in by_seed.values())  # one answer per start/goal
    feasible = sum(v == {True} for v in by_seed.values())
    assert 0 < feasible < 12  # this small set has both kinds
    planner = [r for r in rows if r.policy == "roadmap planner"]
    assert all(r.metrics["success"] == r.metrics["feasible"] for r in planner)
    families = {"nav": plots["nav"]["family"]}
    summary = {s["policy"]: s for s in summarise(rows, families)}
    for entry in summary.values():
        assert entry["feasible"] == pytest.approx(feasible / 12) and entry["feasible_n"] == 12
        assert entry["success_feasible_n"] == feasible
    assert summary["roadmap planner"]["success_feasible"] == 1.0
    table = format_table(list(summary.values()), families)
    header = table.splitlines()[1]
    assert "feasible" in header and "success_feasible" in header and "ticks_to_goal" in header
    assert f"1.000 [{summary['roadmap planner']['success_feasible_lo']:.3f}, 1.000] " \
           f"n={feasible}" in table


def test_plan_cost_is_read_from_info_when_the_env_reports_it():
    episode = navigation.NavigationEpisode(env=None, checks=None)
    assert episode.metrics({"is_success": True, "ticks_to_goal": 12, "plan_cost": 212.0}) == {
        "success": True, "ticks_to_goal": 12, "plan_cost": 212.0}
    assert episode.metrics({"is_success": False}) == {"success": False}
    rows = [EpisodeResult("e", "p", s, 5, t, -1.0, {"success": True, "plan_cost": c})
            for s, (t, c) in enumerate([(10, 10.0), (12, 112.0), (20, 20.0)])]
    (entry,) = summarise(rows, {"e": navigation.FAMILY})
    assert entry["plan_cost"] == pytest.approx(142 / 3) and entry["plan_cost_n"] == 3


def _row(policy, seed, success, ticks):
    return EpisodeResult("e", policy, seed, 3, ticks, -ticks, {"success": success})


def test_the_oracle_takes_the_best_fixed_angle_of_each_seed():
    rows = [_row("fixed 45°", 10_000, False, 50), _row("fixed 90°", 10_000, True, 40),
            _row("fixed 135°", 10_000, True, 30),  # success, fewest ticks
            _row("fixed 45°", 10_001, False, 60), _row("fixed 90°", 10_001, False, 60),
            _row("fixed 135°", 10_001, False, 70),  # a tie: the first angle of Φ
            _row("random", 10_001, True, 5)]  # not a fixed angle: never chosen
    fixed = ["fixed 45°", "fixed 90°", "fixed 135°"]
    oracle = best_fixed_in_hindsight(rows, fixed, navigation.FAMILY)
    assert [(r.policy, r.seed, r.metrics["oracle_choice"], r.ticks) for r in oracle] == [
        (ORACLE_NAME, 10_000, "fixed 135°", 30), (ORACLE_NAME, 10_001, "fixed 45°", 60)]
    assert best_fixed_in_hindsight(rows, fixed[:1], navigation.FAMILY) == []


def test_rl_rows_are_one_row_of_runs_with_the_two_level_bootstrap():
    rates = [0.2, 0.5, 0.6, 0.7, 0.9]
    rows = [EpisodeResult("e", f"rl ppo_seed{k}", 10_000 + i, 4, 10, 0.0,
                          {"success": i < round(10 * rate)}, "rl ppo")
            for k, rate in enumerate(rates) for i in range(10)]
    rows += [EpisodeResult("e", "random", 10_000 + i, 4, 10, 0.0, {"success": i < 3})
             for i in range(10)]
    shown, per_seed = table_rows(rows, {"e": navigation.FAMILY})
    assert [r["policy"] for r in shown] == ["rl ppo", "random"]  # variants: test_wrappers
    assert [r["policy"] for r in per_seed] == [f"rl ppo_seed{k}" for k in range(5)]
    ppo = shown[0]
    runs = [[i < round(10 * rate) for i in range(10)] for rate in rates]
    expected = stats.row_estimate(runs)
    assert (ppo["success"], ppo["success_lo"], ppo["success_hi"]) == pytest.approx(
        (expected.value, expected.lo, expected.hi))
    assert ppo["success"] == pytest.approx((0.5 + 0.6 + 0.7) / 3)  # the middle 50% of seeds
    # the episodes are resampled too: two seeds with the same mean are not a point interval
    # (the audit's two-seed row read 0.863 [0.860, 0.865] while each seed alone was ±0.05)
    same = [[i < 5 for i in range(10)], [i >= 5 for i in range(10)]]
    assert stats.iqm_estimate([0.5, 0.5]).hi == stats.iqm_estimate([0.5, 0.5]).lo
    both = stats.row_estimate(same)
    assert both.value == 0.5 and both.lo < 0.35 and both.hi > 0.65
    assert (ppo["seeds"], ppo["episodes"], ppo["success_n"]) == (5, 50, 50)
    random = shown[1]
    assert "seeds" not in random and random["success_n"] == 10
    assert (random["success"], random["success_lo"], random["success_hi"]) == pytest.approx(
        tuple(getattr(stats.row_estimate([[i < 3 for i in range(10)]]), k)
              for k in ("value", "lo", "hi")))
    table = format_table(shown, {"e": navigation.FAMILY})
    assert "seeds" in table.splitlines()[1] and f"{ppo['success']:.3f} [" in table


def test_a_learner_row_with_fewer_than_five_seeds_is_marked():
    rows = [EpisodeResult("e", f"rl dqn_seed{k}", 10_000 + i, 4, 10, 0.0, {"success": i < 5},
                          "rl dqn") for k in range(2) for i in range(10)]
    shown, _ = table_rows(rows, {"e": navigation.FAMILY})
    assert "e           rl dqn [2 seeds < 5]  20" in format_table(shown, {"e": navigation.FAMILY})


def test_results_record_provenance_config_seeds_and_interval_columns(tmp_path, capsys):
    config = {"name": "tiny", "output": str(tmp_path / "runs"), "models": str(tmp_path / "m"),
              "experiments": [_square(seeds={"start": 10_000, "count": 4},
                                      policies=["planner", "random", "fixed", "rl"])]}
    note = (f"nav: no trained models in {tmp_path / 'm' / 'nav'} (<algo>_seed<N>.zip), so no rl "
            "rows; no shipped training configuration makes them")
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress",
                          "--tables"]) == 0
    out, err = capsys.readouterr()
    table = [line for line in out.splitlines() if line.startswith("nav ")]
    assert table and all(len(CELL.findall(line)) >= 5 for line in table)
    assert f"warning: {note}" in err
    (folder,) = (tmp_path / "runs").iterdir()
    results = json.loads((folder / "results.json").read_text())
    made = results["provenance"]
    assert set(made["packages"]) == set(PACKAGES)
    assert made["packages"]["numpy"] == np.__version__
    assert re.fullmatch(r"[0-9a-f]{40}", made["git"]["commit"])  # this checkout's commit
    assert isinstance(made["git"]["dirty"], bool) and made["python"].count(".") == 2
    exp = results["config"]["experiments"][0]
    assert exp["seeds"] == [10_000, 10_001, 10_002, 10_003] and exp["max_steps"] == 200
    assert results["seeds"] == {"nav": [10_000, 10_001, 10_002, 10_003]}
    assert results["notes"] == [note]
    with (folder / "summary.csv").open(encoding="utf-8") as fh:
        summary = list(csv.DictReader(fh))
    for column in ("success", "feasible", "success_feasible", "ticks", "return"):
        assert {f"{column}_lo", f"{column}_hi", f"{column}_n"} <= set(summary[0])
    oracle = next(s for s in summary if s["policy"] == ORACLE_NAME)
    assert oracle["episodes"] == "4"


def test_git_state_outside_a_checkout_or_without_git_is_unknown(tmp_path, monkeypatch):
    assert git_state(tmp_path) == {"commit": "unknown", "dirty": None}

    def no_git(*args, **kwargs):
        raise FileNotFoundError("git")

    monkeypatch.setattr("bounce_gym.provenance.subprocess.run", no_git)
    assert provenance()["git"] == {"commit": "unknown", "dirty": None}


def test_a_second_model_folder_with_the_privileged_observation(tmp_path):
    """An agent trained with the true pose in its observation runs on its own copy of the env,
    on the same episodes; a missing folder is a warning, not a crash."""
    train_config = {"name": "nav-priv", "env": NAV,
                    "env_kwargs": dict(SQUARE, privileged=True), "algo": "ppo",
                    "total_timesteps": 64, "n_envs": 1,
                    "hyperparams": {"n_steps": 32, "batch_size": 32},
                    "models": str(tmp_path / "models")}
    assert train.main([str(_write(tmp_path / "t.yaml", train_config)), "--no-progress"]) == 0
    exp = _square(seeds={"start": 10_000, "count": 3}, policies=["fixed", "rl"],
                  rl_models=["nav", {"folder": "nav-priv", "env_kwargs": {"privileged": True}}])
    config = {"name": "priv", "output": str(tmp_path / "runs"),
              "models": str(tmp_path / "models"), "experiments": [exp]}
    rows, plots = run(config, progress=False)
    # the folder's observation holds the pose: its rows say so
    privileged = [r for r in rows if r.policy == "rl nav-priv/ppo_seed0 (pose observed)"]
    assert [r.seed for r in privileged] == [10_000, 10_001, 10_002]
    assert {r.group for r in privileged} == {"rl nav-priv/ppo (pose observed)"}
    fixed = {r.seed: r.metrics["feasible"] for r in rows if r.policy == "fixed 90°"}
    assert {r.seed: r.metrics["feasible"] for r in privileged} == fixed  # the same episodes
    assert plots["nav"]["warnings"] == [f"nav: no trained models in {tmp_path / 'models' / 'nav'} "
                                     "(<algo>_seed<N>.zip), so no rl rows; no shipped training "
                                     "configuration makes them"]
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    assert (folder / "nav-profile.png").stat().st_size > 1000
    results = json.loads((folder / "results.json").read_text())
    assert [s["policy"] for s in results["per_seed"]] == [
        "rl nav-priv/ppo_seed0 (pose observed)", "rl nav-priv/ppo_seed0 (pose observed) (greedy)"]
    assert {"rl nav-priv/ppo (pose observed)", "rl nav-priv/ppo (pose observed) (greedy)"} <= \
        {s["policy"] for s in results["summary"]}
