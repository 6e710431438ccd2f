"""evaluate.py / train.py with the multi-robot PettingZoo envs (bounce_gym_experiments.runner with the
multi-robot families)."""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from baselines.policy import FixedAnglePolicy, RandomAnglePolicy
from baselines.rl.train import validate_train_config
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym_experiments import stats
from bounce_gym_experiments.config import configs_folder, load_config, validate_config
from bounce_gym_experiments.families import multirobot_coverage, multirobot_monitoring
from bounce_gym_experiments.oracle import ORACLE_NAME
from bounce_gym_experiments.report import format_table, summarise
from bounce_gym_experiments.runner import (
    EpisodeResult,
    make_experiment_env,
    prepare_experiment,
    run,
    run_episode,
)

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402
import train  # noqa: E402

COVERAGE = "bounce_gym/MultiBounceCoverage-v0"
MONITORING = "bounce_gym/MultiBounceMonitoring-v0"
GRID = {"world": "grid_10x10", "backend": "cell", "step_mode": "tick", "angles": [45, 90, 135],
        "corner_rule": "no_squeeze", "turn_angles": [45, -45]}
HALVES = [[[0, 0], [5, 0], [5, 10], [0, 10]], [[5, 0], [10, 0], [10, 10], [5, 10]]]
REASON = "sized for a quick test"


def coverage_exp(name="cov", m=2, **extra) -> dict:
    exp = {"name": name, "env": COVERAGE,
           "env_kwargs": dict(GRID, n_robots=m, robot_collisions="bounce"),
           "seeds": [10_000, 10_001], "max_steps": 3000, "horizon_reason": REASON,
           "policies": ["random", "fixed"]}
    exp.update(extra)
    return exp


def monitoring_exp(**extra) -> dict:
    exp = {"name": "mon", "env": MONITORING,
           "env_kwargs": dict(GRID, n_robots=2, robot_collisions="ignore",
                              task_kwargs={"regions": HALVES}),
           "seeds": [10_000, 10_001, 10_002], "max_steps": 200, "horizon_reason": REASON,
           "policies": ["planner", "random"],
           "planner_kwargs": {"phi": 90}}
    exp.update(extra)
    return exp


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


# -- configuration ------------------------------------------------------------------------------

@pytest.mark.parametrize(
    ("exp", "message"),
    [
        ({"name": "a", "env": "bounce_gym/MultiBounceNope-v0"}, r"\.env: unknown environment"),
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "planner_kwargs": {"phi": 90}},
         r"\.planner_kwargs: bouncing experiments take no planner options"),
        (coverage_exp(planner_kwargs=[135]), r"\.planner_kwargs: expected dict"),
        (coverage_exp(rl_models="../elsewhere"), r"\.rl_models: expected the name of a folder"),
        (coverage_exp(rl_models=3), r"\.rl_models: expected str or list"),
        (coverage_exp(rl_models=["a", {"folder": "b", "env_kwargs": {"world": "square"}}]),
         r"\.rl_models\[1\]\.env_kwargs: only observation options"),
        (coverage_exp(rl_models=["a", "a"]), r"\.rl_models: a folder is named twice"),
        (coverage_exp(visibility={"start": 0, "goal": 1}), r"\.visibility: only for single"),
        (coverage_exp(env_kwargs=dict(GRID, max_cycles=10)), r"env_kwargs\.max_cycles"),
        (coverage_exp(policies=["oracle"]), r"\.policies: unknown"),
    ],
)
def test_bad_multi_experiments_raise(exp, message):
    with pytest.raises(ConfigError, match=message):
        validate_config({"experiments": [exp]})


@pytest.mark.parametrize(
    ("exp", "message"),
    [
        (coverage_exp(policies=["planner"], env_kwargs=dict(GRID, turn_angles=[90])),
         "turn_angles"),
        (coverage_exp(policies=["planner"], planner_kwargs={"colour": 1}), "planner_kwargs"),
        (coverage_exp(policies=["planner"], planner_kwargs={"phi": 180}),
         "phi: 180° is not among"),
        ({"name": "free", "env": "bounce_gym/MultiBounce-v0", "env_kwargs": GRID,
          "policies": ["planner"]}, "no multi-robot planner for task 'free'"),
        (coverage_exp(env_kwargs={"world": "grid_10x10", "action_type": "continuous"}),
         "action_type"),
    ],
)
def test_multi_policies_that_cannot_apply_raise(exp, message):
    with pytest.raises(ConfigError, match=message):
        run({"experiments": [exp]}, progress=False)


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"name": "a", "env": COVERAGE, "algo": "dqn", "total_timesteps": 10}, "algo"),
        ({"name": "a", "env": COVERAGE, "algo": "recurrentppo", "total_timesteps": 10}, "algo"),
        ({"name": "a", "env": COVERAGE, "algo": "ppo", "total_timesteps": 10, "n_envs": 2},
         "n_envs"),
        ({"name": "a", "env": "bounce_gym/MultiNope-v0", "algo": "ppo", "total_timesteps": 10},
         "config.env"),
    ],
)
def test_bad_multi_training_configs_raise(config, message):
    with pytest.raises(ConfigError, match=message):
        validate_train_config(config)


# -- episodes and metrics -------------------------------------------------------------------------

def test_random_and_fixed_rows_on_a_small_coverage_experiment():
    exp = coverage_exp(m=3, max_steps=800)
    rows, plots = run({"experiments": [exp]}, progress=False)
    fixed = ("fixed 45°", "fixed 90°", "fixed 135°")
    assert [(r.policy, r.seed) for r in rows] == [
        (p, s) for s in (10_000, 10_001) for p in ("random", *fixed)] + [
        (ORACLE_NAME, s) for s in (10_000, 10_001)]
    for r in rows[-2:]:  # the best fixed angle of the seed: fewest (capped) steps to full
        mine = [q for q in rows if q.seed == r.seed and q.policy in fixed]  # coverage, ticks
        best = max(mine, key=lambda q: (-q.metrics["steps_to_full_capped"], -q.ticks))
        assert r.metrics["oracle_choice"] == best.policy and r.steps == best.steps
    for r in rows:
        assert r.metrics["robots"] == 3 and 0 < r.metrics["coverage"] <= 1.0
        full = r.metrics["steps_to_full"]
        assert (full is None) == (r.metrics["coverage"] < 1.0)
        assert r.steps == (full if full is not None else 800) == r.ticks
    random_rows = [r for r in rows if r.policy == "random"]
    assert all(r.metrics["steps_to_full"] is not None for r in random_rows)
    assert plots["cov"]["paths"]["random"].shape[1:] == (3, 2)
    # a fresh run gives the same rows: policies restart their randomness from the seed
    again, _ = run({"experiments": [exp]}, progress=False)
    assert [r.row() for r in again] == [r.row() for r in rows]


def test_random_bouncing_never_sends_a_turn_command():
    env = MultiBounceEnv(**GRID, n_robots=3, task="coverage")
    policy = RandomAnglePolicy(seed=0)
    obs, infos = env.reset(seed=0)
    policy.reset(env)
    chosen = {a for _ in range(300) for a in policy.act(obs, infos).values()}
    assert chosen == {0, 1, 2}  # all of Φ, never 3 or 4 (the turn commands)


def test_steps_to_full_matches_a_hand_run_episode():
    exp = coverage_exp(m=3, seeds=[10_005], policies=["fixed"])
    rows, _ = run({"experiments": [exp]}, progress=False)
    row = next(r for r in rows if r.policy == "fixed 135°")
    env = make_experiment_env(validate_config({"experiments": [exp]})["experiments"][0])
    env.reset(seed=10_005)
    first, contacts = None, 0
    for step in range(1, 3001):
        _, _, _, _, infos = env.step(dict.fromkeys(env.agents, 2))
        state = env.unwrapped.core.state
        contacts += int(np.sum(state.blocked & (state.contact_robot >= 0)))
        if infos["robot_0"]["coverage"] >= 1.0:
            first = step
            break
    assert first is not None and row.metrics["steps_to_full"] == first == row.steps
    assert row.metrics["robot_contacts"] == contacts


def test_summary_gives_intervals_and_the_count_of_covered_episodes():
    rows = [EpisodeResult("e", "p", s, steps, steps, 0.0,
                          {"robots": 3, "full": full is not None, "steps_to_full": full,
                           "coverage": cov})
            for s, (steps, full, cov) in enumerate([(10, 10, 1.0), (30, 30, 1.0), (50, None, 0.5)])]
    families = {"e": multirobot_coverage.FAMILY}
    (entry,) = summarise(rows, families)
    assert entry["robots"] == 3 and isinstance(entry["robots"], int) and "robots_n" not in entry
    # a conditional mean: over the two covered episodes only, and it says so
    assert (entry["steps_to_full"], entry["steps_to_full_n"]) == (20.0, 2)
    assert (entry["steps_to_full_lo"], entry["steps_to_full_hi"]) == (10.0, 30.0)
    assert entry["coverage"] == pytest.approx(2.5 / 3) and entry["coverage_n"] == 3
    # full coverage is a rate: 2 of 3, with the same bootstrap as every cell
    assert (entry["full"], entry["full_n"]) == (pytest.approx(2 / 3), 3)
    assert (entry["full_lo"], entry["full_hi"]) == (0.0, 1.0)
    table = format_table([entry], families)
    assert "multi-robot coverage" in table and "20.0 [10.0, 30.0] n=2" in table
    assert "0.667 [0.000, 1.000] n=3" in table and "±" not in table


def test_encounters_count_pairs_together_at_the_end_of_a_step():
    same = {"start": {"position": [[2.5, 0.5], [2.5, 0.5], [8.5, 8.5]], "heading": [0, 0, 0]}}
    for backend, extra in (("cell", {}), ("kinematic", {"robot_radius": 0.3})):
        env = MultiBounceEnv(world="grid_10x10", n_robots=3, task="monitoring", backend=backend,
                             step_mode="tick", robot_collisions="ignore", **extra)
        env.reset(seed=0, options=same)
        _, _, _, _, infos = env.step(dict.fromkeys(env.agents, 0))
        assert infos["robot_0"]["encounters"] == 1  # robots 0 and 1 drive together; 2 is apart
        assert "in_region_fraction" in infos["robot_0"] and "robot_contacts" in infos["robot_0"]


def test_monitoring_rows_report_region_time_encounters_and_r():
    exp = monitoring_exp(planner_kwargs={"phi": 90, "start": "cycle"})
    rows, _ = run({"experiments": [exp]}, progress=False)
    planner = [r for r in rows if r.policy == "planner (cycle start)"]
    assert len(planner) == 3 and len(rows) == 6
    for r in planner:  # an accepted group of Algorithm 2: collision-free, every period
        assert r.metrics["r"] > 0 and r.metrics["encounters"] == 0 and r.metrics["period"] > 0
        assert 0 < r.metrics["in_region"] <= 1 and r.steps == 200
        assert 0 < r.metrics["predicted_in_region"] < 1
    summary = {s["policy"]: s for s in summarise(rows, {"mon": multirobot_monitoring.FAMILY})}
    assert "in_region_lo" in summary["random"] and "r" not in summary["random"]
    planned = summary["planner (cycle start)"]
    assert planned["r"] == planner[0].metrics["r"] and "r_n" not in planned


def test_monitoring_planner_from_the_drawn_start_predicts_nothing():
    rows, _ = run({"experiments": [monitoring_exp()]}, progress=False)
    planner = [r for r in rows if r.policy == "planner"]
    assert len(planner) == 3
    for r in planner:
        assert r.metrics["r"] > 0
        assert "period" not in r.metrics and "predicted_in_region" not in r.metrics


def _benchmark_monitoring(start: str):
    """The benchmark's monitoring experiment of ``start``, its trained agents included,
    prepared for three seeds."""
    name = {"draw": "multirobot-monitoring-15x15",
            "cycle": "multirobot-monitoring-15x15-cycle-start"}[start]
    (exp,) = (e for e in load_config(configs_folder() / "benchmark.yaml")["experiments"]
              if e["name"] == name)
    assert exp["planner_kwargs"]["start"] == start
    exp.update(seeds=[10_000, 10_001, 10_002], max_steps=1, horizon_reason=REASON)
    config = validate_config({"models": str(ROOT / "baselines" / "agents"),
                              "experiments": [exp]})
    return prepare_experiment(config["experiments"][0], Path(config["models"]), "exp")


def _start_pose(env) -> np.ndarray:
    state = env.unwrapped.robot_state
    return np.column_stack([state.position, state.heading])


@pytest.mark.parametrize("start", ["draw", "cycle"])
def test_every_monitoring_policy_starts_where_the_experiment_says(start):
    """``start: draw``: every policy (the planner too) starts at a plain ``env.reset(seed)``;
    ``start: cycle``: every policy starts on the planner's cycle start for the seed."""
    prepared = _benchmark_monitoring(start)
    names = [e.policy.name for e in prepared.entrants]
    planner = {"draw": "planner", "cycle": "planner (cycle start)"}[start]
    assert names[:5] == [planner, "random", "fixed 45°", "fixed 90°", "fixed 135°"]
    assert any(n.startswith("rl ") for n in names)
    plain = make_experiment_env(prepared.experiment)
    moved = False
    for seed in prepared.experiment["seeds"]:
        plain.reset(seed=seed)
        drawn = _start_pose(plain)
        if start == "cycle":
            plain.reset(seed=seed, options=prepared.setup.cycle_options(seed))
            expected = _start_pose(plain)
            moved |= not np.allclose(expected, drawn)
        else:
            expected = drawn
        for e in prepared.entrants:
            episode = prepared.family.episode(e.env, e.policy, e.setup)
            run_episode(e.env, e.policy, seed, 0, episode)
            assert np.allclose(_start_pose(e.env), expected), (e.policy.name, seed)
    if start == "cycle":  # the cycle start is not the draw on every seed
        assert moved


def test_monitoring_start_is_checked():
    with pytest.raises(ConfigError, match=r"^config\.experiments\[0\]\.planner_kwargs\.start: "
                                          r"expected one of \['draw', 'cycle'\], got 'best'$"):
        validate_config({"experiments": [monitoring_exp(planner_kwargs={"start": "best"})]})
    default = validate_config({"experiments": [monitoring_exp()]})["experiments"][0]
    assert default["planner_kwargs"] == {"phi": 90, "start": "draw"}


def test_coverage_planner_rows_reproduce_the_predicted_steps():
    """On the cell backend the env executes Algorithm 1's joint trajectory exactly: the env's
    first full-coverage step is the plan's steps_to_full."""
    exp = coverage_exp(m=3, seeds=[10_000, 10_001, 10_002], max_steps=5000, policies=["planner"],
                       planner_kwargs={"phi": 135})
    rows, _ = run({"experiments": [exp]}, progress=False)
    assert len(rows) == 3
    for r in rows:
        assert r.metrics["predicted_steps_to_full"] is not None
        assert r.metrics["steps_to_full"] == r.metrics["predicted_steps_to_full"] == r.steps


# -- training and the evaluate CLI ----------------------------------------------------------------

@pytest.mark.slow  # trains a shared PPO through train.py, then evaluates: ~45 s on two cores
def test_shared_ppo_trained_by_train_py_is_scored_by_evaluate(tmp_path):
    train_config = {"name": "shared", "env": COVERAGE,
                    "env_kwargs": dict(GRID, n_robots=3, max_cycles=100),
                    "algo": "ppo", "total_timesteps": 384, "seed": 0,
                    "hyperparams": {"n_steps": 64, "batch_size": 64, "n_epochs": 2},
                    "models": str(tmp_path / "models")}
    assert train.main([str(_write(tmp_path / "t.yaml", train_config)), "--no-progress"]) == 0
    assert (tmp_path / "models/shared/ppo_seed0.zip").is_file()
    experiments = [coverage_exp(f"m{m}", m=m, seeds=[10_000, 10_001], max_steps=800,
                                policies=["rl", "random"], rl_models="shared")
                   for m in (3, 4)]
    config = {"name": "rl", "output": str(tmp_path / "runs"), "models": str(tmp_path / "models"),
              "experiments": experiments}
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    results = json.loads((folder / "results.json").read_text())
    scored = [e for e in results["episodes"] if e["policy"] == "rl ppo_seed0"]
    assert [(e["experiment"], e["seed"], e["group"]) for e in scored] == [
        ("m3", 10_000, "rl ppo"), ("m3", 10_001, "rl ppo"), ("m4", 10_000, "rl ppo"),
        ("m4", 10_001, "rl ppo")]
    summary = {(s["experiment"], s["policy"]): s for s in results["summary"]}
    # the table shows one row per algorithm over its training seeds (here one seed)
    ppo = summary[("m3", "rl ppo")]
    assert ppo["seeds"] == 1 and ppo["episodes"] == 2 and ppo["coverage_n"] == 2
    assert ("m3", "rl ppo_seed0") not in summary
    # beside it the same model greedy: every robot its most likely action
    assert summary[("m3", "rl ppo (greedy)")]["episodes"] == 2
    per_seed = {(s["experiment"], s["policy"]): s for s in results["per_seed"]}
    assert ppo["coverage"] == per_seed[("m3", "rl ppo_seed0")]["coverage"]
    assert all((summary[(m, "random")]["full"], summary[(m, "random")]["full_n"]) == (1.0, 2)
               for m in ("m3", "m4"))
    for name in ("m3-trajectories", "m3-visits", "steps-vs-robots-grid_10x10-cell"):
        assert (folder / f"{name}.png").stat().st_size > 1000
    # a model for other action spaces is refused with the field named
    wrong = dict(experiments[0], env_kwargs=dict(GRID, n_robots=3, turn_angles=[]))
    with pytest.raises(ConfigError, match="ppo_seed0.zip: trained for"):
        run({"models": str(tmp_path / "models"), "experiments": [wrong]}, progress=False)


@pytest.mark.slow  # a whole multi-robot evaluation through the CLI: ~19 s
def test_evaluate_cli_prints_multi_tables_with_intervals(tmp_path, capsys):
    config = {"name": "multi", "output": str(tmp_path / "runs"),
              "experiments": [coverage_exp(seeds=[10_000, 10_001, 10_002], policies=["random"]),
                              monitoring_exp(seeds=[10_000])]}
    assert evaluate.main([str(_write(tmp_path / "c.yaml", config)), "--no-progress",
                          "--tables"]) == 0
    out = capsys.readouterr().out
    assert "multi-robot coverage" in out and "multi-robot monitoring" in out
    assert "n=3" in out and "n=1" in out and "±" not in out
    (folder,) = (tmp_path / "runs").iterdir()
    summary = json.loads((folder / "results.json").read_text())["summary"]
    cov = next(s for s in summary if s["experiment"] == "cov")
    steps = [e for e in json.loads((folder / "results.json").read_text())["episodes"]
             if e["experiment"] == "cov"]
    values = [e["steps_to_full"] for e in steps]
    assert (cov["steps_to_full_lo"], cov["steps_to_full_hi"]) == stats.bootstrap_mean_interval(
        values)
    assert cov["full"] == 1.0 and cov["full_n"] == 3
    assert math.isclose(cov["steps_to_full"], np.mean(values))
    assert (folder / "mon-trajectories.png").is_file()


def test_fixed_policy_names_and_actions():
    policy = FixedAnglePolicy(2, 135.0)
    assert policy.name == "fixed 135°"
    policy.reset(MultiBounceEnv(**GRID, n_robots=2))
    assert policy.act({"robot_0": None, "robot_1": None}, {}) == {"robot_0": 2, "robot_1": 2}
    # a goal-conditioned Gymnasium env's observation is a dict too, of one robot
    import gymnasium as gym

    policy.reset(gym.make("bounce_gym/BounceNavigation-v1"))
    assert policy.act({"observation": None, "achieved_goal": None, "desired_goal": None}, {}) == 2


def test_an_episode_capped_before_full_coverage():
    env = MultiBounceEnv(**GRID, n_robots=2, task="coverage", max_cycles=50)
    episode = multirobot_coverage.CoverageEpisode(env)
    summary, path = run_episode(env, FixedAnglePolicy(0, 45.0), seed=0, max_steps=50,
                                episode=episode, record=True)
    metrics = episode.metrics(summary["info"])
    assert metrics["steps_to_full"] is None and summary["steps"] == 50
    assert metrics["coverage"] < 1.0
    assert path.shape == (51, 2, 2)
