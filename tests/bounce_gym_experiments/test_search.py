"""The hyperparameter search (`bounce_gym_experiments.search`, `bounce_gym_experiments.search_space`): the search
space's checks, reproducible draws, and a tiny search on a local Ray instance whose trials are
ordinary training runs, with the trials table and the best entry ready for a hyperparameter
file."""

import csv
import sys
from pathlib import Path

import pytest
import yaml

from baselines.rl.model_files import read_model
from baselines.rl.train_config import validate_train_config
from baselines.seeds import EVALUATION_SEEDS, TRAINING_SEEDS, TUNING_SEEDS
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.search import trial_configs
from bounce_gym_experiments.search_space import load_search_space, sample_trial

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))
CONFIG = {"name": "nav", "env": "bounce_gym/BounceNavigation-v0",
          "env_kwargs": {"world": "square", "backend": "cell", "angles": [90, 135]},
          "algo": "ppo", "total_timesteps": 256, "seed": 0, "n_envs": 2,
          "hyperparams": {"n_steps": 64, "batch_size": 64, "n_epochs": 1}}
SPACE = {"learning_rate": {"loguniform": [1.0e-4, 1.0e-3]}, "gamma": {"uniform": [0.9, 0.99]},
         "n_epochs": {"randint": [1, 3]}, "batch_size": {"choice": [32, 64]}}


def _space(tmp_path: Path, space: object) -> Path:
    path = tmp_path / "space.yaml"
    path.write_text(yaml.safe_dump(space), encoding="utf-8")
    return path


@pytest.mark.parametrize("space, message", [
    ([1, 2], "search: .* must map hyperparameter names to distributions"),
    ({"gamma": 0.99}, r"search.gamma: expected one of \{loguniform, uniform, randint, choice"),
    ({"gamma": {"normal": [0, 1]}}, "search.gamma: expected one of"),
    ({"gamma": {"uniform": [0.99, 0.9]}}, r"search.gamma.uniform: expected \[low, high\], "
                                          "numbers with low < high, got \\[0.99, 0.9\\]"),
    ({"learning_rate": {"loguniform": [0, 1]}}, "search.learning_rate.loguniform: .* 0 < low"),
    ({"n_epochs": {"randint": [1.5, 3]}}, "search.n_epochs.randint: expected .* integers"),
    ({"n_epochs": {"randint": [3]}}, "search.n_epochs.randint: expected"),
    ({"batch_size": {"choice": []}},
     "search.batch_size.choice: expected a list of 1 to 10000 values, got 0 values"),
])
def test_a_bad_search_space_names_the_field(tmp_path, space, message):
    with pytest.raises(ConfigError, match=message):
        load_search_space(_space(tmp_path, space))


def test_a_missing_space_file_and_a_non_hyperparameter_are_refused(tmp_path):
    with pytest.raises(ConfigError, match="search: file .* does not exist"):
        load_search_space(tmp_path / "none.yaml")
    config = {**CONFIG, "models": str(tmp_path / "models")}
    with pytest.raises(ConfigError, match="search: trial 0 .*config.hyperparams.colour: not a "
                                          "hyperparameter of PPO"):
        trial_configs(config, _space(tmp_path, {"colour": {"choice": ["red"]}}), 2, 0)


def test_trials_train_and_are_scored_on_training_seeds_only(tmp_path):
    """A trial trains on the configuration's first seed and is scored on its own training
    episodes (the monitor file): every env seed it uses is a training seed, never a tuning or
    evaluation one, and a first seed whose envs would reach the tuning seeds is refused."""
    config = {key: value for key, value in CONFIG.items() if key != "seed"}
    config.update(models=str(tmp_path / "models"), seeds=[TRAINING_SEEDS.stop - 2, 5])
    for _, trial in trial_configs(config, _space(tmp_path, SPACE), 3, 0):
        assert trial["seeds"] == [TRAINING_SEEDS.stop - 2]
        env_seeds = range(trial["seeds"][0], trial["seeds"][0] + trial["n_envs"])
        assert all(s in TRAINING_SEEDS for s in env_seeds)
        assert not any(s in TUNING_SEEDS or s in EVALUATION_SEEDS for s in env_seeds)
    with pytest.raises(ConfigError, match=r"search: trial 0 .*config\.seeds: seed 8999 with "
                                          r"n_envs 2 would seed envs up to 9000"):
        trial_configs({**config, "seeds": [TRAINING_SEEDS.stop - 1]}, _space(tmp_path, SPACE),
                      1, 0)


def test_draws_are_reproducible_and_within_their_bounds(tmp_path):
    space = load_search_space(_space(tmp_path, SPACE))
    draws = [sample_trial(space, 7, k) for k in range(20)]
    assert draws == [sample_trial(space, 7, k) for k in range(20)]
    assert draws[0] != sample_trial(space, 8, 0)
    assert all(1.0e-4 <= d["learning_rate"] <= 1.0e-3 and 0.9 <= d["gamma"] <= 0.99 and
               d["n_epochs"] in (1, 2, 3) and d["batch_size"] in (32, 64) for d in draws)
    assert {d["n_epochs"] for d in draws} == {1, 2, 3}
    assert all(isinstance(d["n_epochs"], int) for d in draws)


@pytest.mark.slow  # ~15 s: a Ray instance and four training trials
def test_a_tiny_search_on_a_local_ray_writes_ordinary_runs_a_table_and_the_best_entry(
        tmp_path, capsys):
    pytest.importorskip("ray")
    from bounce_gym_experiments.cli import main

    config = tmp_path / "t.yaml"
    config.write_text(yaml.safe_dump({**CONFIG, "models": str(tmp_path / "models")}),
                      encoding="utf-8")
    assert main(["tune", str(config), "--space", str(_space(tmp_path, SPACE)), "--trials", "3",
                 "--workers", "2", "--metric", "success", "--scheduler", "asha",
                 "--no-progress"]) == 0
    folder = tmp_path / "models" / "nav-tune"
    rows = list(csv.DictReader((folder / "trials.csv").open(encoding="utf-8")))
    assert [r["trial"] for r in rows] == ["0", "1", "2"]
    # ASHA may stop a trial early (it keeps its checkpoints, saves no model)
    assert {r["status"] for r in rows} <= {"finished", "stopped early"}
    assert set(rows[0]) == {"trial", "status", "success", "episodes", "env_steps", *SPACE}
    for k, row in enumerate(rows):
        assert (folder / f"ppo-trial{k}_seed0.monitor.csv").is_file()
        if row["status"] == "finished":
            model = read_model(folder / f"ppo-trial{k}_seed0.zip")  # listed in the manifest
            assert model.metadata["config"]["hyperparams"]["n_epochs"] == int(row["n_epochs"])
    out = capsys.readouterr().out
    assert f"wrote {folder}/trials.csv and {folder}/best_hyperparams.yaml" in out
    best = yaml.safe_load((folder / "best_hyperparams.yaml").read_text(encoding="utf-8"))
    entry = best["bounce_gym/BounceNavigation-v0"]
    winner = max((r for r in rows if r["status"] == "finished"),
                 key=lambda r: float(r["success"]))
    assert entry["n_epochs"] == int(winner["n_epochs"]) and entry["n_timesteps"] == 256
    # the entry is a hyperparameter file's: a configuration trains from it as it is
    again = validate_train_config({"name": "x", "env": "bounce_gym/BounceNavigation-v0",
                                   "env_kwargs": CONFIG["env_kwargs"], "algo": "ppo",
                                   "hyperparams_file": str(folder / "best_hyperparams.yaml")})
    assert again["hyperparams"]["learning_rate"] == pytest.approx(float(
        winner["learning_rate"]), rel=1e-5)


def test_draws_reach_the_ends_of_int64_without_overflow(tmp_path):
    space = load_search_space(_space(tmp_path, {"seed_like": {"randint": [2**63 - 2,
                                                                          2**63 - 1]}}))
    assert {sample_trial(space, 0, k)["seed_like"] for k in range(40)} == {2**63 - 2, 2**63 - 1}


@pytest.mark.parametrize("space, message", [
    ({"n_steps": {"randint": [1, 2**63]}}, r"search.n_steps.randint: expected \[low, high\], "
                                           "integers in"),
    ({"n_steps": {"randint": [10, 2**40]}}, r"search.n_steps.randint\[1\]: expected an integer "
                                            r"in \[1, 1000000\]"),
    ({"gae_lambda": {"uniform": [-0.5, 0.5]}}, r"search.gae_lambda.uniform\[0\]: expected a "
                                               r"number in \[0, 1\], got -0.5"),
    ({"ent_coef": {"choice": [0.0, -1]}}, r"search.ent_coef.choice\[1\]: expected a number >= 0"),
    ({"policy_kwargs": {"choice": [{"net_arch": [64]}, 3]}}, None),  # checked per trial
])
def test_the_bounds_of_a_search_space_lie_within_the_hyperparameters_ranges(tmp_path, space,
                                                                             message):
    if message is None:
        assert load_search_space(_space(tmp_path, space))
        return
    with pytest.raises(ConfigError, match=message):
        load_search_space(_space(tmp_path, space))
