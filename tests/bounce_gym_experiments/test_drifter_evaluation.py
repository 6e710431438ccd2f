"""evaluate.py with the drifter families (bounce_gym_experiments.families.drifters, drifter_deployment):
tables with intervals, the value-iteration policy's measured success against the model's
prediction, and the deployments' coverage."""

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import stats as scipy_stats

from baselines.drifters import (
    deployment_locations,
    expected_coverage,
    group_coverage,
    persistent_behavior,
    visit_probabilities,
)
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow
from bounce_gym_experiments import stats
from bounce_gym_experiments.config import configs_folder, load_config, validate_config
from bounce_gym_experiments.families import drifter_deployment, drifters
from bounce_gym_experiments.registry import world_name
from bounce_gym_experiments.report import families_of, summarise
from bounce_gym_experiments.runner import prepare_experiment, run

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402
import train  # noqa: E402

REACH = "bounce_gym/Drifter-v0"
FLEET = "bounce_gym/MultiDrifter-v0"
CELL = re.compile(r"-?\d+(\.\d+)? \[(-?\d+(\.\d+)?, -?\d+(\.\d+)?|-, -)\] n=\d+")
TWO_SINK_FLEET = 5  # Alg. 5.2's deployment cells on two_sink's surface

#: the value iteration row: it acts on the drifter's true model state (info["state"])
VI = "value iteration (pose observed)"


def reach(name="reach", count=3, **kwargs) -> dict:
    return {"name": name, "env": REACH, "env_kwargs": {"observe_fix": True, **kwargs},
            "seeds": {"start": 10_000, "count": count}, "policies": ["planner", "random", "fixed"]}


def deployment(name="deploy", count=3, **extra) -> dict:
    exp = {"name": name, "env": FLEET,
           "env_kwargs": {"flow": "two_sink", "n_drifters": TWO_SINK_FLEET},
           "seeds": {"start": 10_000, "count": count}, "policies": ["planner", "random"]}
    exp.update(extra)
    return exp


def config(tmp_path, *experiments) -> dict:
    return {"name": "drifters", "output": str(tmp_path / "runs"),
            "models": str(tmp_path / "models"), "experiments": list(experiments)}


def test_a_tiny_drifter_evaluation_reports_every_cell_with_an_interval(tmp_path, capsys):
    short = {"max_steps": 40, "horizon_reason": "a quick test"}
    path = tmp_path / "drifters.yaml"
    path.write_text(yaml.safe_dump(config(
        tmp_path, reach(), {**reach("reach-continuous", 2, backend="continuous"), **short},
        {**deployment(), **short})), encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--tables"]) == 0
    out = capsys.readouterr().out
    assert "drifters: reach the goal (Alg. 5.5)" in out
    assert "drifter deployment: surface coverage (Alg. 5.2)" in out
    rows = {(line.split()[0], " ".join(line.split()[1:3])): line for line in out.splitlines()
            if line.startswith(("reach", "deploy"))}
    for policy in (VI, "random layer", "always drift"):
        line = next(v for (exp, p), v in rows.items() if exp == "reach" and policy.startswith(p))
        assert len(CELL.findall(line)) >= 2  # success and return at least, each with an interval
    (folder,) = (tmp_path / "runs").iterdir()
    summary = {(r["experiment"], r["policy"]): r
               for r in json.loads((folder / "results.json").read_text())["summary"]}
    planner = summary[("reach", VI)]
    assert planner["success_n"] == 3 and planner["predicted_success_n"] == 3
    assert 0 <= planner["success_lo"] <= planner["success"] <= planner["success_hi"] <= 1
    assert "predicted_success" in summary[("reach", "always drift")]
    assert "predicted_success" not in summary[("reach", "random layer")]
    for policy in ("Alg. 5.2 deployment", "greedy deployment (H=40)", "random deployment"):
        row = summary[("deploy", policy)]
        assert row["drifters"] == TWO_SINK_FLEET and row["coverage_n"] == 3
        assert row["coverage_lo"] <= row["coverage"] <= row["coverage_hi"]
        assert "predicted_coverage" in row
    for name in ("reach-policy", "reach-flow", "reach-trajectories", "reach-continuous-policy",
                 "deploy-coverage", "deploy-deployment", "deploy-trajectories"):
        assert (folder / f"{name}.png").stat().st_size > 1000


def test_value_iteration_success_on_the_cell_backend_is_the_models_prediction(tmp_path):
    """Seeds 10,000-10,199: the measured successes are a draw of the sum of independent
    Bernoulli(p_i), p_i the model's reach probability from episode i's start (the cell env is
    the model); the table's interval for the success rate holds the mean prediction."""
    exp = {**reach(count=200), "policies": ["planner"]}
    rows, plots = run(config(tmp_path, exp), progress=False)
    assert {r.policy for r in rows} == {VI}
    success = np.array([r.metrics["success"] for r in rows], dtype=float)
    p = np.array([r.metrics["predicted_success"] for r in rows])
    assert 0.2 < p.mean() < 0.8  # neither certain nor hopeless: the test can tell them apart
    z = (success.sum() - p.sum()) / np.sqrt(np.sum(p * (1 - p)))
    assert abs(z) < scipy_stats.norm.ppf(0.999)
    (row,) = summarise(rows, families_of(plots))
    assert row["success_lo"] <= row["predicted_success"] <= row["success_hi"]


def test_always_drift_prediction_is_the_drift_chain(tmp_path):
    """The always-drift row's prediction is the reach probability of the drift chain alone."""
    exp = {**reach(count=4), "policies": ["fixed"]}
    prepared = prepare_experiment(validate_config(config(tmp_path, exp))["experiments"][0],
                                  tmp_path, "x")
    env = prepared.env
    _, info = env.reset(seed=10_000)
    model = env.unwrapped.cell_model()
    goal = env.unwrapped.task.region.states
    hit = np.zeros(model.n_states)
    hit[goal] = 1.0
    at_goal = np.isin(np.arange(model.n_states), goal)
    for _ in range(200):  # the goal is absorbing: once there, the drifter stays counted
        hit = np.where(at_goal, 1.0, model.drift_matrix() @ hit)
    predicted = prepared.setup(env, prepared.entrants[0].policy, info["state"])
    assert predicted == pytest.approx(hit[info["state"]], abs=1e-12)
    env.close()


def test_the_deployments_use_alg_5_2s_fleet_size_and_their_predicted_coverage(tmp_path):
    exp = deployment(count=20)
    rows, plots = run(config(tmp_path, exp), progress=False)
    by_policy: dict[str, list] = {}
    for r in rows:
        by_policy.setdefault(r.policy, []).append(r)
    assert set(by_policy) == {"Alg. 5.2 deployment", "greedy deployment (H=500)",
                              "random deployment"}
    model = DrifterCells(get_flow("two_sink"))
    n_cells = len(model.layer_states(0))
    setup = plots["deploy"]["setup"]
    for policy, mine in by_policy.items():
        assert all(r.metrics["drifters"] == TWO_SINK_FLEET for r in mine)
        curves = np.array(setup.curves[policy])
        assert curves.shape == (20, 501)
        # every curve starts from the five distinct release cells of its episode
        assert np.allclose(curves[:, 0], TWO_SINK_FLEET / n_cells)
        assert np.all(np.diff(curves, axis=1) >= 0)
        measured = np.array([r.metrics["coverage"] for r in mine])
        assert np.allclose(curves[:, -1], measured)
        # the cell env's coverage is what the model expects of the deployment
        predicted = np.array([r.metrics["predicted_coverage"] for r in mine])
        ci = stats.bootstrap_mean_interval(measured - predicted)
        assert ci[0] <= 0 <= ci[1]
    alg = np.mean([r.metrics["coverage"] for r in by_policy["Alg. 5.2 deployment"]])
    greedy = np.mean([r.metrics["coverage"] for r in by_policy["greedy deployment (H=500)"]])
    assert greedy > alg  # the greedy deployment maximises exactly this expectation


def test_alg_5_2_reaches_every_surface_cell_eventually_and_its_groups_surely():
    """Theory (thesis §5.4.3, Alg. 5.2): from its deployment cells every surface cell of
    two_sink is visited with positive probability eventually — each from a deployment cell of
    its own group (group-wise coverage, which no random fleet of the same size achieves here) —
    and the cells of a persistent group with probability 1 by the drifter released in it.
    Positive is not likely: the expected share of cells the fleet ever visits is small, which
    the evaluation measures (the env's coverage is the model's, tested above)."""
    model = DrifterCells(get_flow("two_sink"))
    behavior = persistent_behavior(model, 0)
    ever = visit_probabilities(behavior, None)
    chosen = deployment_locations(behavior, seed=0).states - behavior.offset
    assert len(chosen) == TWO_SINK_FLEET
    assert np.all((ever[chosen] > 0).any(axis=0))
    for group in behavior.groups:
        (released,) = [z for z in chosen if z + behavior.offset in group]
        assert ever[released, group - behavior.offset] == pytest.approx(1.0, abs=1e-6)
    assert group_coverage(behavior, chosen + behavior.offset).all()
    rng = np.random.default_rng(0)
    random_sets = [behavior.offset + rng.choice(behavior.n_cells, TWO_SINK_FLEET, replace=False)
                   for _ in range(20)]
    assert not any(group_coverage(behavior, s).all() for s in random_sets)
    assert expected_coverage(behavior, chosen + behavior.offset, ever) < 0.2


def test_a_fleet_of_the_wrong_size_or_a_kind_the_family_does_not_run_is_an_error(tmp_path):
    wrong = deployment()
    wrong["env_kwargs"]["n_drifters"] = 4
    with pytest.raises(ConfigError, match=r"n_drifters: Alg\. 5\.2 deploys 5 drifters.*set "
                                          r"n_drifters: 5"):
        run(config(tmp_path, wrong), progress=False)
    with pytest.raises(ConfigError, match=r"experiments\[0\]\.policies: unknown \['fixed'\]; "
                                          r"drifter-deployment experiments run "
                                          r"\['planner', 'random'\]$"):
        run(config(tmp_path, deployment(policies=["random", "fixed"])), progress=False)
    # without the planner the fleet size is free: random cells for any number of drifters
    rows, _ = run(config(tmp_path, {**wrong, "policies": ["random"]}), progress=False)
    assert {r.metrics["drifters"] for r in rows} == {4}


def test_the_families_are_the_drifter_ones_and_the_leaderboard_names_the_flow(tmp_path):
    prepared = prepare_experiment(validate_config(config(tmp_path, reach()))["experiments"][0],
                                  tmp_path, "x")
    assert prepared.family is drifters.FAMILY
    prepared.env.close()
    prepared = prepare_experiment(
        validate_config(config(tmp_path, deployment()))["experiments"][0], tmp_path, "x")
    assert prepared.family is drifter_deployment.FAMILY
    prepared.env.close()
    assert world_name(reach()) == "scb_like"
    assert world_name(deployment()) == "two_sink"


def test_the_shipped_drifter_configs_validate():
    config = validate_config(load_config(configs_folder() / "eval_drifters.yaml"))
    envs = {e["env"] for e in config["experiments"]}
    assert envs == {REACH, FLEET}
    for exp in config["experiments"]:
        assert exp["seeds"][0] >= 10_000 and "horizon_reason" not in exp
    backends = {e["env_kwargs"].get("backend", "cell") for e in config["experiments"]
                if e["env"] == REACH}
    assert backends == {"cell", "continuous"}


def test_a_drifter_agent_trains_with_the_shipped_config_and_joins_the_table(tmp_path):
    train_config = yaml.safe_load((configs_folder() / "train_drifter.yaml").read_text())
    train_config.update(total_timesteps=512, n_envs=2, hyperparams={"n_steps": 128},
                        seeds=[0], models=str(tmp_path / "models"),
                        hyperparams_file=str(configs_folder() / "hyperparams/ppo.yaml"))
    train_config.pop("checkpoint_every")
    path = tmp_path / "train.yaml"
    path.write_text(yaml.safe_dump(train_config), encoding="utf-8")
    assert train.main([str(path), "--no-progress"]) == 0
    exp = {**reach(count=2), "policies": ["rl"], "rl_models": "drifter-reach"}
    rows, _ = run(config(tmp_path, exp), progress=False)
    assert [r.policy for r in rows] == ["rl ppo_seed0", "rl ppo_seed0 (greedy)"] * 2
    assert all("success" in r.metrics and "predicted_success" not in r.metrics for r in rows)


def test_a_relative_flow_file_is_read_next_to_the_config(tmp_path):
    from bounce_gym.flows import save_flow

    (tmp_path / "fields").mkdir()
    save_flow(get_flow("two_sink"), tmp_path / "fields" / "basin.nc")
    exp = {**reach(count=1), "env_kwargs": {"flow": "fields/basin.nc", "goal": (0, 10, 10)},
           "policies": ["planner"]}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(config(tmp_path, exp)), encoding="utf-8")
    loaded = load_config(path)
    assert loaded["experiments"][0]["env_kwargs"]["flow"] == str(tmp_path / "fields/basin.nc")
    rows, _ = run(loaded, progress=False)
    assert len(rows) == 1 and "predicted_success" in rows[0].metrics
    assert world_name(loaded["experiments"][0]) == "basin.nc"


def test_the_sampled_planner_rows_beside_the_old_one(tmp_path):
    """planner_kwargs.models runs Alg. 5.5 on the cell model and the plan on the sampled GCM
    on the same episodes; the sampled one's predicted_success is its own model's."""
    exp = {**reach("reach-sampled", 2, backend="continuous", observe_pose=True),
           "policies": ["planner"], "max_steps": 20, "horizon_reason": "a quick test",
           "planner_kwargs": {"models": ["cell", "sampled"], "samples": 4}}
    rows, _ = run(config(tmp_path, exp), progress=False)
    assert {r.policy for r in rows} == {VI, "value iteration (sampled GCM) (pose observed)"}
    assert all(0 <= r.metrics["predicted_success"] <= 1 for r in rows)


@pytest.mark.parametrize("kwargs, message", [
    ({"models": ["learned"]}, "planner_kwargs.models"), ({"colour": 1}, "planner_kwargs: unknown")])
def test_bad_drifter_planner_kwargs_raise(tmp_path, kwargs, message):
    exp = {**reach(count=1), "policies": ["planner"], "planner_kwargs": kwargs}
    with pytest.raises(ConfigError, match=message):
        run(config(tmp_path, exp), progress=False)
