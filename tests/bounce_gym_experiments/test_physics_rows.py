"""The evaluation configs' rows on the pymunk backend's dynamic physics (issue 23): each stands
next to the same task on the kinematic or cell backend, differing only in the motion model, and
every one of them runs through evaluate.py (two seeds, a short horizon). The navigation row of
the planner on the sampled GCM (issue 24) runs with a tiny model."""

import json
import sys
from pathlib import Path

import pytest
import yaml

from baselines.policy import Policy
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.config import load_config, validate_config
from bounce_gym_experiments.families.navigation import navigation_planners
from bounce_gym_experiments.runner import make_experiment_env, run_episode

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402

CONFIGS = ["eval_default.yaml", "eval_multirobot.yaml", "eval_physics.yaml"]
DYNAMIC = {"backend": "pymunk", "physics": "dynamic"}
#: what may differ between a row and its dynamic sibling: the motion model, the cell model's
#: diagonal rule (cell rows) and the disk radius (point robots exist only on the exact models)
MODEL_KEYS = {"backend", "physics", "corner_rule", "robot_radius"}
#: the sampled planner's rows (issue 24): kinematic without noise, kinematic and dynamic with
SAMPLED_ROWS = ("navigation-lab-sampled-kinematic", "navigation-lab-sampled-noise-kinematic",
                "navigation-lab-sampled-noise-pymunk-dynamic")
#: the continuous-angle planner's rows: kinematic without and with rotation noise
CONTINUOUS_ROWS = ("navigation-lab-continuous-kinematic",
                   "navigation-lab-continuous-noise-kinematic")
#: the sampled planner's options in the quick runs: a coarse model of few samples (on the lab,
#: 21 positions x 8 bins; the dynamic row's model, sampled on pymunk, costs 4 s to build, 7.6 s
#: with cells of 1.0), a short look-ahead
TINY = {"samples": 2, "cell_size": 1.5, "depth": 1, "reach": 3}


def _experiments(name: str) -> list[dict]:
    """The configuration's experiments as written, ``env_kwargs`` filled in where left out."""
    return [{"env_kwargs": {}, **exp} for exp in load_config(ROOT / "configs" / name)["experiments"]]


def _dynamic(exp: dict) -> bool:
    return all(exp["env_kwargs"].get(k) == v for k, v in DYNAMIC.items())


def _sampled(exp: dict) -> bool:
    return "sampled" in exp.get("planner_kwargs", {}).get("models", ())


def _continuous(exp: dict) -> bool:
    return exp["env_kwargs"].get("action_type") == "continuous"


def _rest(exp: dict) -> tuple:
    """The task: env, its options but the motion model (and for the sampled planner's rows the
    rotation noise), and the planner's arguments (seeds, horizons and policies may differ:
    dynamic rows run fewer episodes in the quick configs)."""
    skip = MODEL_KEYS | ({"noise"} if _sampled(exp) else set())
    kwargs = {k: v for k, v in exp["env_kwargs"].items() if k not in skip}
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
    experiments = _experiments("eval_physics.yaml")
    assert [e["name"] for e in experiments if _sampled(e)] == list(SAMPLED_ROWS)
    noisy = {e["name"]: "noise" in e["env_kwargs"] for e in experiments if _sampled(e)}
    assert noisy == {name: "noise" in name for name in SAMPLED_ROWS}
    assert [e["name"] for e in experiments if _continuous(e)] == list(CONTINUOUS_ROWS)
    names = {e["name"] for e in experiments if not _sampled(e) and not _continuous(e)}
    stems = {n.rsplit("-", 1)[0].removesuffix("-pymunk") for n in names}
    for stem in stems:
        assert {f"{stem}-cell", f"{stem}-kinematic", f"{stem}-pymunk-ideal",
                f"{stem}-pymunk-dynamic"} <= names, stem


def _summary(tmp_path, rows: list[dict]) -> list[dict]:
    config = {"name": "dyn", "output": str(tmp_path / "runs"), "models": str(tmp_path / "m"),
              "experiments": rows}
    path = tmp_path / "dyn.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--workers", "1"]) == 0
    (folder,) = (tmp_path / "runs").iterdir()
    return json.loads((folder / "results.json").read_text())["summary"]


@pytest.mark.long
def test_every_dynamic_row_runs(tmp_path):
    """Every dynamic row but the sampled planner's (`test_the_sampled_planner_rows_run`)."""
    rows = []
    for name in CONFIGS:
        for exp in _experiments(name):
            if _dynamic(exp) and not _sampled(exp) \
                    and exp["name"] not in {r["name"] for r in rows}:
                rows.append(dict(exp, seeds=[10_000, 10_001], max_steps=12,
                                 horizon_reason="a quick test", rl_models=[]))
    for row in rows:
        row.pop("rl_models")
    summary = _summary(tmp_path, rows)
    done = {(s["experiment"], s["policy"]) for s in summary}
    for row in rows:
        ran = {policy for experiment, policy in done if experiment == row["name"]}
        assert len(ran) >= 2, f"{row['name']}: {ran}"  # the planner and random bouncing


def test_the_sampled_planner_rows_run(tmp_path):
    """The sampled planner's rows with a tiny model: both planners run, with the prediction
    (a probability), the feasibility and the success on feasible episodes in their columns."""
    rows = [dict(exp, seeds=[10_000], max_steps=6, horizon_reason="a quick test",
                 planner_kwargs={**exp["planner_kwargs"], **TINY})
            for exp in _experiments("eval_physics.yaml") if exp["name"] in SAMPLED_ROWS]
    summary = _summary(tmp_path, rows)
    for row in rows:
        ran = {s["policy"]: s for s in summary if s["experiment"] == row["name"]}
        assert set(ran) == {"roadmap planner (open loop)", "sampled-gcm"}, row["name"]
        sampled = ran["sampled-gcm"]
        assert sampled["predicted_success_n"] == 1
        assert 0.0 <= sampled["predicted_success"] <= 1.0
        for policy in ran.values():
            assert policy["feasible_n"] == 1
            assert ("success_feasible" in policy) == (policy["feasible"] == 1.0)
        assert "predicted_success" not in ran["roadmap planner (open loop)"]


def test_the_continuous_planner_rows_run(tmp_path):
    """The continuous-angle planner's rows, one short episode each: the planner and random
    bouncing run, with the cell feasibility, the world reachability and the prediction."""
    rows = [dict(exp, seeds=[10_002], max_steps=6, horizon_reason="a quick test")
            for exp in _experiments("eval_physics.yaml") if exp["name"] in CONTINUOUS_ROWS]
    summary = _summary(tmp_path, rows)
    for row in rows:
        ran = {s["policy"]: s for s in summary if s["experiment"] == row["name"]}
        assert set(ran) == {"continuous-angle planner", "random"}, row["name"]
        planner = ran["continuous-angle planner"]
        assert planner["predicted_success_n"] == 1 and 0.0 <= planner["predicted_success"] <= 1
        for policy in ran.values():
            assert policy["feasible_n"] == policy["world_reachable_n"] == 1
            assert ("success_world_reachable" in policy) == (policy["world_reachable"] == 1.0)


@pytest.mark.parametrize(("action_type", "models"), [("discrete", ["continuous"]),
                                                     ("continuous", ["roadmap", "continuous"])])
def test_the_planners_must_take_the_env_actions(action_type, models):
    (exp,) = (dict(e, env_kwargs={**e["env_kwargs"], "action_type": action_type},
                   planner_kwargs={"models": models})
              for e in _experiments("eval_physics.yaml") if e["name"] == CONTINUOUS_ROWS[0])
    with pytest.raises(ConfigError, match="take continuous actions, the others discrete"):
        validate_config({"experiments": [exp]})


class Blind(Policy):
    """The same policy, handed an empty ``info`` at every step."""

    def __init__(self, policy: Policy) -> None:
        self.policy = policy

    def reset(self, env) -> None:
        self.policy.reset(env)

    def act(self, observation, info):
        return self.policy.act(observation, {})


def test_the_sampled_planner_reads_no_info_in_the_evaluation():
    """The evaluation loop hands the env's ``info`` to the policy; the sampled planner's episode
    is the same without it."""
    (exp,) = (dict(e, planner_kwargs={**e["planner_kwargs"], **TINY, "models": ["sampled"]},
                   max_steps=8, horizon_reason="a quick test")
              for e in _experiments("eval_physics.yaml") if e["name"] == SAMPLED_ROWS[0])
    env = make_experiment_env(exp)
    ((_, planner),) = navigation_planners(exp)
    seen, _ = run_episode(env, planner, 10_000, exp["max_steps"], record=True)
    blind, _ = run_episode(env, Blind(planner), 10_000, exp["max_steps"], record=True)
    assert seen["steps"] == blind["steps"] and seen["ticks"] == blind["ticks"]
    assert seen["info"]["position"] == pytest.approx(blind["info"]["position"])


def test_agents_trained_on_another_motion_model_say_so():
    """The lab coverage agents were trained on the cell backend: on pymunk's dynamic physics
    their rows are named "(trained on cell)"."""
    from bounce_gym_experiments.families.base import trained_motion_model
    from bounce_gym_experiments.runner import prepare_experiment

    folder = ROOT / "baselines" / "agents" / "coverage-lab"
    assert {trained_motion_model(path) for path in folder.glob("*.zip")} == {"cell"}
    experiment = validate_config({"name": "t", "models": "baselines/agents", "experiments": [{
        "name": "c", "env": "bounce_gym/BounceCoverage-v0", "seeds": [10_000],
        "policies": ["rl"], "rl_models": "coverage-lab",
        "env_kwargs": {"world": "lab_fig1", "cell_bins": 360, "angles": [30, 75, 315],
                       **DYNAMIC}}]})["experiments"][0]
    prepared = prepare_experiment(experiment, folder.parent, "e")
    assert {entrant.group for entrant in prepared.entrants} == {
        "rl ppo (trained on cell)", "rl ppo (trained on cell) (greedy)"}
