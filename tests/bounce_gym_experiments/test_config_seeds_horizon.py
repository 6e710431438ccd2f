"""Evaluation configurations: held-out seeds, the {start, count} shorthand, the registered
horizon and when it may differ, model folders."""

import pytest
import yaml

from baselines.seeds import EVALUATION_SEEDS_START
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.config import load_config, registered_horizon, validate_config
from bounce_gym_experiments.runner import make_experiment_env

NAV = "bounce_gym/BounceNavigation-v0"
COVERAGE = "bounce_gym/MultiBounceCoverage-v0"
GOAL = "bounce_gym/BounceNavigation-v1"


def _one(**exp) -> dict:
    return validate_config({"experiments": [{"name": "a", "env": NAV, **exp}]})["experiments"][0]


def test_seeds_default_to_the_first_evaluation_seed_and_expand_from_start_and_count():
    assert EVALUATION_SEEDS_START == 10_000
    assert _one()["seeds"] == [10_000]
    assert _one(seeds={"start": 10_000, "count": 200})["seeds"] == list(range(10_000, 10_200))
    assert _one(seeds=[10_003, 10_001])["seeds"] == [10_003, 10_001]


@pytest.mark.parametrize(("seeds", "message"), [
    ([0, 1], r"config\.experiments\[0\]\.seeds: evaluation seeds must not overlap the training "
             r"seeds \[0, 9000\) \(baselines\.seeds\), got \[0, 1\]$"),
    ([10_000, 9_999], r"^config\.experiments\[0\]\.seeds: evaluation seeds must not overlap the "
                      r"tuning seeds \[9000, 10000\) \(baselines\.seeds\), got \[9999\]$"),
    ([9_500, 3], r"\.seeds: .* the tuning seeds \[9000, 10000\) .*got \[9500\]$"),
    ([-1, 10_001], r"\.seeds: evaluation seeds must be >= 10000 \(baselines\.seeds\), got \[-1\]"),
    (list(range(7)), r"got \[0, 1, 2, 3, 4\] \.\.\."),
    ([10_000, 10_000], r"\.seeds: every seed once .*repeated: \[10000\]"),
    ([], r"\.seeds: expected a non-empty list"),
    ([True], r"\.seeds: expected a non-empty list of integers"),
    ({"start": 5, "count": 10}, r"^config\.experiments\[0\]\.seeds: evaluation seeds must not "
                                r"overlap the training seeds \[0, 9000\) \(baselines\.seeds\), "
                                r"got start 5, count 10$"),
    ({"start": 9_990, "count": 200}, r"^config\.experiments\[0\]\.seeds: evaluation seeds must "
                                     r"not overlap the tuning seeds \[9000, 10000\)"),
    ({"start": -20, "count": 10}, r"\.seeds\.start: expected an integer in \[10000, 4294967295\], "
                                  r"got -20"),
    ({"start": 10_000, "count": 0}, r"\.seeds\.count: expected an integer in \[1, 100000\], got 0"),
    ({"start": 10_000}, r"\.seeds: missing key 'count'"),
    ({"start": 10_000, "count": 2, "step": 3}, r"\.seeds: unknown keys \['step'\]"),
    ({"start": 10_000, "count": "many"}, r"\.seeds\.count: expected int, got str"),
    ("10000", r"\.seeds: expected list or dict, got str"),
])
def test_bad_seeds_name_the_field(seeds, message):
    with pytest.raises(ConfigError, match=message):
        _one(seeds=seeds)


def test_the_horizon_is_the_registered_one_unless_a_reason_is_given():
    assert registered_horizon(NAV) == 200 and registered_horizon(COVERAGE) == 500
    assert _one()["max_steps"] == 200
    assert _one(max_steps=200)["max_steps"] == 200
    exp = _one(max_steps=50, horizon_reason="a shorter study")
    assert exp["max_steps"] == 50
    assert make_experiment_env(exp).spec.max_episode_steps == 50  # the env stops where the loop does
    multi = validate_config({"experiments": [{"name": "m", "env": COVERAGE}]})["experiments"][0]
    assert multi["max_steps"] == 500


@pytest.mark.parametrize(("exp", "message"), [
    ({"max_steps": 100}, r"config\.experiments\[0\]\.max_steps: 100 differs from the horizon 200 "
                         r"that bounce_gym/BounceNavigation-v0 registers \(and training uses\)"),
    ({"horizon_reason": "why not"}, r"\.horizon_reason: only with a max_steps that differs from "
                                    r"the registered horizon 200"),
    ({"max_steps": 200, "horizon_reason": "same"}, r"\.horizon_reason: only with a max_steps"),
    ({"max_steps": 100, "horizon_reason": "  "}, r"\.horizon_reason: expected a non-empty"),
    ({"max_steps": 0, "horizon_reason": "none"}, r"\.max_steps: expected an integer in \[1, 1000000\]"),
    ({"env_kwargs": {"max_episode_steps": 10}}, r"\.env_kwargs\.max_episode_steps: not allowed"),
])
def test_bad_horizons_name_the_field(exp, message):
    with pytest.raises(ConfigError, match=message):
        _one(**exp)


def test_model_folders_become_a_list_and_validation_is_idempotent():
    config = {"experiments": [
        {"name": "nav", "env": NAV, "policies": ["rl"], "seeds": {"start": 10_000, "count": 3}},
        {"name": "nav2", "env": NAV, "policies": ["random"], "max_steps": 20,
         "horizon_reason": "quick", "difficulty": "hard",
         "rl_models": ["nav", {"folder": "nav-priv", "env_kwargs": {"privileged": True}}]}]}
    valid = validate_config(config)
    first, second = valid["experiments"]
    assert first["rl_models"] == [{"folder": "nav", "env_kwargs": {}}]
    assert second["rl_models"] == [{"folder": "nav", "env_kwargs": {}},
                                   {"folder": "nav-priv", "env_kwargs": {"privileged": True}}]
    assert validate_config(valid) == valid
    assert valid["leaderboard"] is False
    with pytest.raises(ConfigError, match=r"\.difficulty: expected one of \('easy', 'medium', "
                                          r"'hard'\), got 'brutal'"):
        _one(difficulty="brutal")


def test_relative_map_files_are_read_next_to_the_config(tmp_path):
    (tmp_path / "maps").mkdir()
    config = {"experiments": [{"name": "a", "env": NAV,
                               "env_kwargs": {"world": "maps/box.yaml"}},
                              {"name": "b", "env": NAV, "env_kwargs": {"world": "square"}}]}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    loaded = load_config(path)
    assert loaded["experiments"][0]["env_kwargs"]["world"] == str(tmp_path / "maps/box.yaml")
    assert loaded["experiments"][1]["env_kwargs"]["world"] == "square"


def test_a_v1_experiment_runs_the_horizon_of_its_map():
    grid = {"world": "configs/maps/bench_grid_14x22.yaml"}
    lab = _one(env=GOAL)
    assert lab["max_steps"] == 42
    exp = _one(env=GOAL, env_kwargs=grid)
    assert exp["max_steps"] == 60 == make_experiment_env(exp).spec.max_episode_steps
    with pytest.raises(ConfigError, match=r"max_steps: 42 differs from the horizon 60 that "
                                          r"bounce_gym/BounceNavigation-v1 derives on this map"):
        _one(env=GOAL, env_kwargs=grid, max_steps=42)
    longer = _one(env=GOAL, env_kwargs=grid, max_steps=80, horizon_reason="a longer study")
    assert make_experiment_env(longer).spec.max_episode_steps == 80
