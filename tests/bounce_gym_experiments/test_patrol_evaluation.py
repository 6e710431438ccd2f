"""evaluate.py with the patrolling family (bounce_gym_experiments.families.patrolling): the table with
intervals, the best response's measured capture rate against the env's prediction, detection
times, and the configuration's errors."""

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from baselines.patrolling import solve_maect
from baselines.patrolling.policies import (
    BestResponseAdversary,
    JointPatrolPolicy,
    MarkovPatrolPolicy,
)
from bounce_gym.errors import ConfigError
from bounce_gym_experiments import stats
from bounce_gym_experiments.config import validate_config
from bounce_gym_experiments.families import patrolling
from bounce_gym_experiments.runner import make_experiment_env, prepare_experiment, run, run_episode

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402

PATROL = "bounce_gym/Patrol-v0"
SMALL = {"world": "grid_10x10", "n_patrollers": 2, "sensor_range": 2.0, "attack_time": 5}
CELL = re.compile(r"-?\d+(\.\d+)? \[(-?\d+(\.\d+)?, -?\d+(\.\d+)?|-, -)\] n=\d+")


def patrol(name="patrol", count=6, **extra) -> dict:
    exp = {"name": name, "env": PATROL, "env_kwargs": dict(SMALL),
           "seeds": {"start": 10_000, "count": count},
           "policies": ["planner", "random", "perimeter"]}
    exp.update(extra)
    return exp


def config(tmp_path, *experiments) -> dict:
    return {"name": "patrol", "output": str(tmp_path / "runs"),
            "models": str(tmp_path / "models"), "experiments": list(experiments)}


def test_a_perimeter_evaluation_writes_its_table_files_and_plots(tmp_path, capsys):
    path = tmp_path / "patrol.yaml"
    path.write_text(yaml.safe_dump(config(tmp_path, patrol(policies=["perimeter"]))),
                    encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--tables"]) == 0
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if line.startswith("patrol ")]
    assert len(lines) == 4 and all(len(CELL.findall(line)) >= 3 for line in lines)
    (folder,) = (tmp_path / "runs").iterdir()
    assert {r["policy"] for r in json.loads((folder / "results.json").read_text())["summary"]} \
        == {f"perimeter {p} vs best response ({m})" for p in ("deterministic", "random_walk")
            for m in ("strategy", "positions")}
    assert len((folder / "episodes.csv").read_text().splitlines()) == 1 + 4 * 6
    assert (folder / "patrol-covers.png").stat().st_size > 1000


@pytest.mark.slow
@pytest.mark.long
def test_a_tiny_patrol_evaluation_reports_every_rate_with_an_interval(tmp_path, capsys):
    """Every patroller kind (the GλD fits of the p_d plot take most of its ~20 s)."""
    path = tmp_path / "patrol.yaml"
    path.write_text(yaml.safe_dump(config(tmp_path, patrol())), encoding="utf-8")
    assert evaluate.main([str(path), "--no-progress", "--tables"]) == 0
    out = capsys.readouterr().out
    assert "patrolling: capture of the adversary (thesis ch. 4)" in out
    lines = [line for line in out.splitlines() if line.startswith("patrol ")]
    patrollers = ("MAECT", "equilibrium mixture", "random walk", "perimeter deterministic",
                  "perimeter random_walk")
    assert len(lines) == 2 * len(patrollers)
    for line in lines:
        assert len(CELL.findall(line)) >= 3  # captured, predicted_capture, deterred
    (folder,) = (tmp_path / "runs").iterdir()
    results = json.loads((folder / "results.json").read_text())
    rows = {r["policy"]: r for r in results["summary"]}
    for patroller in patrollers:
        for adversary in ("best response (strategy)", "best response (positions)"):
            row = rows[f"{patroller} vs {adversary}"]
            assert row["captured_n"] == 6 and row["t_a"] == 5
            assert 0 <= row["captured_lo"] <= row["captured"] <= row["captured_hi"] <= 1
            assert row["predicted_capture_n"] == 6
            captures = round(row["captured"] * 6)
            assert row.get("detection_time_n", 0) == captures  # a mean over the captures
            assert "attack_target" not in row  # a descriptor, not a measurement
    episodes = (folder / "episodes.csv").read_text().splitlines()
    assert len(episodes) == 1 + 6 * 2 * len(patrollers)
    assert "attack_target" in episodes[0] and "outcome" in episodes[0]
    for name in ("patrol-maect-weights", "patrol-covers", "patrol-pd"):
        assert (folder / f"{name}.png").stat().st_size > 1000


def test_the_best_response_is_caught_against_maect_as_often_as_the_env_predicts():
    """400 held-out episodes of MAECT against the best response told the strategy: the
    capture rate's Wilson interval holds the env's exact capture probability of the target,
    and the target is the one of least capture probability."""
    kwargs = {**SMALL, "sensor_range": 3.0, "attack_time": 10}
    exp = validate_config({"experiments": [patrol(policies=["random"], env_kwargs=kwargs)]}
                          )["experiments"][0]
    env = make_experiment_env(exp)
    maect = solve_maect(env.unwrapped.graph).transition
    adversary = BestResponseAdversary("strategy")
    policy = JointPatrolPolicy(MarkovPatrolPolicy([maect], name="MAECT"), adversary)
    captured = []
    for seed in range(10_000, 10_400):
        episode = patrolling.PatrolEpisode(env, 5)
        summary, _ = run_episode(env, policy, seed, exp["max_steps"], episode)
        captured.append(episode.metrics(summary["info"])["captured"])
    predicted = env.unwrapped.capture_probabilities()
    assert adversary.target == int(np.argmin(predicted))
    assert 0.15 < predicted[adversary.target] < 0.85  # the test can tell rates apart
    rate = stats.rate(captured)
    assert rate.lo <= predicted[adversary.target] <= rate.hi
    env.close()


class FixedTarget(BestResponseAdversary):
    """Attacks a given vertex at step 0."""

    def __init__(self, target: int) -> None:
        super().__init__("strategy")
        self.fixed = target

    def reset(self, env):
        super().reset(env)
        self.target = self.fixed


def test_detection_time_is_zero_when_a_patroller_watches_the_target_at_the_start():
    exp = validate_config({"experiments": [patrol(policies=["random"])]})["experiments"][0]
    env = make_experiment_env(exp)
    inner = env.unwrapped

    class Placed(MarkovPatrolPolicy):
        def start_options(self, env, seed):
            super().start_options(env, seed)
            return {"start": [0, inner.n_vertices - 1]}

    walk = Placed([inner.strategy])
    at_start = patrolling.PatrolEpisode(env, 5)
    summary, _ = run_episode(env, JointPatrolPolicy(walk, FixedTarget(0)), 10_000, 100, at_start)
    assert at_start.metrics(summary["info"])["detection_time"] == 0
    assert summary["steps"] == 1
    env.close()


@pytest.mark.parametrize(
    ("exp", "message"),
    [
        (patrol(adversaries=["oracle"]), r"experiments\[0\]\.adversaries: unknown \['oracle'\]; "
                                         r"patrolling experiments run \['best_response', "),
        (patrol(adversaries=[]), r"experiments\[0\]\.adversaries: expected a non-empty"),
        (patrol(adversaries=["best_response", "best_response"]), r"\.adversaries: each"),
        (patrol(adversaries="best_response"), r"\.adversaries: expected list"),
        (patrol(policies=["fixed"]), r"experiments\[0\]\.policies: unknown \['fixed'\]"),
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "adversaries": ["best_response"]},
         r"experiments\[0\]\.adversaries: bouncing experiments have no adversaries"),
        ({"name": "a", "env": "bounce_gym/Bounce-v0", "policies": ["perimeter"]},
         r"experiments\[0\]\.policies: unknown \['perimeter'\]"),
    ],
)
def test_bad_patrol_experiments_raise_naming_the_field(exp, message):
    with pytest.raises(ConfigError, match=message):
        validate_config({"experiments": [exp]})


def test_bad_planner_kwargs_or_env_kwargs_raise_naming_the_field(tmp_path):
    for exp, message in ((patrol(planner_kwargs={"colour": 1}), "planner_kwargs: .*colour"),
                         (patrol(planner_kwargs={"exposed": 0}), "planner_kwargs.exposed"),
                         (patrol(env_kwargs={**SMALL, "attack_time": 0}),
                          r"experiments\[0\]\.env_kwargs: attack_time")):
        with pytest.raises(ConfigError, match=message):
            run(config(tmp_path, exp), progress=False)


def test_the_default_patroller_kinds_and_adversaries():
    exp = validate_config({"experiments": [{"name": "p", "env": PATROL}]})["experiments"][0]
    assert exp["policies"] == ["planner", "random", "perimeter", "rl"]
    assert exp["adversaries"] == ["best_response", "best_response_positions"]


def test_the_family_is_the_patrolling_one(tmp_path):
    exp = validate_config(config(tmp_path, patrol(policies=["random"])))["experiments"][0]
    prepared = prepare_experiment(exp, tmp_path, "x")
    assert prepared.family is patrolling.FAMILY
    assert [e.policy.name for e in prepared.entrants] == [
        "random walk vs best response (strategy)", "random walk vs best response (positions)"]
    prepared.env.close()


def test_trained_patrollers_and_adversaries_meet_every_opponent(tmp_path):
    """Tiny PPO models of both sides (baselines.rl.patrol) in two folders of rl_models: the
    learned patrollers play the best responses and the learned adversary, which also plays the
    random walk; the learned patrol is told to the best response as the chain it induces."""
    from baselines.rl.train import train

    game = {"world": "square", "cell_size": 2.0, "n_patrollers": 2, "sensor_range": 1.5,
            "attack_time": 4}
    for role, own in (("patrollers", {"adversary": "random"}),
                      ("adversary", {"strategies": ["random_walk"]})):
        train({"name": f"patrol-{role}", "env": PATROL, "role": role,
               "env_kwargs": {**game, **own, "max_cycles": 40}, "algo": "ppo",
               "total_timesteps": 64, "hyperparams": {"n_steps": 64, "batch_size": 64,
                                                      "n_epochs": 1},
               "seed": 7, "models": str(tmp_path / "models")}, progress=False)
    exp = {"name": "learned", "env": PATROL, "env_kwargs": game, "max_steps": 40,
           "horizon_reason": "the models' episodes", "seeds": [10_000, 10_001],
           "policies": ["random", "rl"], "adversaries": ["best_response", "rl"],
           "rl_models": ["patrol-patrollers", "patrol-adversary"]}
    rows, plots = run(config(tmp_path, exp), progress=False)
    patrollers, adversary = "rl patrol-patrollers/ppo_seed7", "rl patrol-adversary/ppo_seed7"
    greedy = adversary + " (greedy)"  # the trained adversary also plays its greedy action
    assert {r.policy for r in rows} == {
        "random walk vs best response (strategy)", "random walk vs " + adversary,
        "random walk vs " + greedy, f"{patrollers} vs best response (strategy)",
        f"{patrollers} vs {adversary}", f"{patrollers} vs {greedy}"}
    groups = {r.policy: r.group for r in rows}
    assert groups[f"{patrollers} vs {adversary}"] == \
        "rl patrol-patrollers/ppo vs rl patrol-adversary/ppo"
    assert groups[f"{patrollers} vs {greedy}"] == \
        "rl patrol-patrollers/ppo vs rl patrol-adversary/ppo (greedy)"
    assert all(r.metrics["outcome"] in ("capture", "success", "deterred") for r in rows)
    learned = next(e for e in plots["learned"]["setup"].learned_patrollers)[0]
    env = make_experiment_env(validate_config(config(tmp_path, exp))["experiments"][0])
    (weight, told), = learned.told(env)
    announced = learned.announced(env)
    for chain in (told, announced):
        assert np.allclose(chain.sum(axis=1), 1.0) and (chain >= 0).all()
    assert np.allclose(np.diag(announced), 0.0)
    env.close()


def test_the_shipped_patrol_configuration_is_valid():
    from bounce_gym_experiments.config import configs_folder, load_config

    experiments = validate_config(load_config(configs_folder() / "eval_patrol.yaml"))
    assert {e["env"] for e in experiments["experiments"]} == {PATROL}
    assert all(min(e["seeds"]) >= 10_000 for e in experiments["experiments"])
