"""Every user mistake in `bounce-gym evaluate|train` is one line ``error: <field>: ...`` on
stderr and exit status 2, reported before any long work."""

import json
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

from experiments.cli import main  # noqa: E402

NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}


def _write(path: Path, data) -> Path:
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data), encoding="utf-8")
    return path


def _one_error(capsys, argv: list[str]) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), captured.err
    assert captured.out == ""  # nothing ran, no table was printed
    return lines[0]


def _experiment(**overrides) -> dict:
    """A small navigation experiment; an override of None leaves the key out."""
    exp = {"name": "a", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
           "seeds": [10_000], "max_steps": 5, "horizon_reason": "a quick test",
           "policies": ["random"], **overrides}
    return {k: v for k, v in exp.items() if v is not None}


@pytest.mark.parametrize(("experiment", "message"), [
    (_experiment(env_kwargs={"colour": 1}),
     "config.experiments[1].env_kwargs: BounceEnv() got an unexpected keyword argument 'colour'"),
    (_experiment(env_kwargs={"task_kwargs": {"colour": 1}}),
     "config.experiments[1].env_kwargs: "),
    (_experiment(env_kwargs={"world": "MAP"}),
     "config.experiments[1].env_kwargs: "),
    (_experiment(seeds=[-1]), "config.experiments[1].seeds: evaluation seeds must be >= 10000"),
    (_experiment(seeds=[3, 10_001]),
     "config.experiments[1].seeds: evaluation seeds must be >= 10000 (training uses the seeds "
     "below it, baselines.seeds), got [3]"),
    (_experiment(seeds={"start": 0, "count": 200}),
     "config.experiments[1].seeds.start: expected an integer in [10000, 4294967295], got 0"),
    (_experiment(max_steps=7, horizon_reason=None),
     "config.experiments[1].max_steps: 7 differs from the horizon 200 that "
     "bounce_gym/BounceNavigation-v0 registers"),
    (_experiment(policies=["rl"], name="../x"),
     "config.experiments[1].name (the folder of its rl models): expected the name of a folder"),
    (_experiment(policies=["rl"], rl_models="../x"),
     "config.experiments[1].rl_models: expected the name of a folder"),
])
def test_evaluate_reports_a_bad_experiment_before_running_any(tmp_path, capsys, experiment,
                                                              message):
    bad_map = _write(tmp_path / "bad.json", json.dumps({"polygon": [[0, 0], [1, 0]]}))
    if experiment["env_kwargs"].get("world") == "MAP":
        experiment["env_kwargs"] = {"world": str(bad_map)}
    config = {"output": str(tmp_path / "runs"),
              "experiments": [_experiment(name="fine"), experiment]}
    line = _one_error(capsys, ["evaluate", str(_write(tmp_path / "c.yaml", config)),
                               "--no-progress"])
    assert line.startswith(f"error: {message}")
    assert not (tmp_path / "runs").exists()


def test_evaluate_checks_the_output_folder_before_running(tmp_path, capsys):
    (tmp_path / "file").write_text("not a folder")
    config = {"output": str(tmp_path / "file" / "x"), "experiments": [_experiment()]}
    line = _one_error(capsys, ["evaluate", str(_write(tmp_path / "c.yaml", config))])
    assert line == (f"error: config.output: cannot write into '{tmp_path / 'file' / 'x'}': "
                    f"'{tmp_path / 'file'}' is not a folder")


@pytest.mark.skipif(sys.platform == "win32" or __import__("os").geteuid() == 0,
                    reason="root writes into read-only folders")
def test_evaluate_refuses_a_read_only_output_folder(tmp_path, capsys):
    (tmp_path / "ro").mkdir(mode=0o500)
    config = {"output": str(tmp_path / "ro" / "runs"), "experiments": [_experiment()]}
    line = _one_error(capsys, ["evaluate", str(_write(tmp_path / "c.yaml", config))])
    assert line.startswith("error: config.output: cannot write into") and "not writable" in line


def test_evaluate_refuses_an_untrusted_model_before_running(tmp_path, capsys):
    (tmp_path / "models" / "a").mkdir(parents=True)
    (tmp_path / "models" / "a" / "ppo_seed0.zip").write_bytes(b"PK")
    config = {"output": str(tmp_path / "runs"), "models": str(tmp_path / "models"),
              "experiments": [_experiment(policies=["random", "rl"])]}
    line = _one_error(capsys, ["evaluate", str(_write(tmp_path / "c.yaml", config))])
    assert "ppo_seed0.zip: is not listed in" in line and "bounce-gym trust" in line


def _train(**overrides) -> dict:
    return {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
            "algo": "ppo", "total_timesteps": 64, "n_envs": 1,
            "hyperparams": {"n_steps": 32, "batch_size": 32}, **overrides}


@pytest.mark.parametrize(("config", "extra", "message"), [
    (None, [], "config: file '"),
    ("name: [unclosed", [], "config: t.yaml: not valid YAML: while parsing a flow sequence, did "
                            "not find expected ',' or ']' at line 2, column 1"),
    (_train(colour=1), [], "config: unknown keys ['colour']"),
    (_train(total_timesteps="many"), [], "config.total_timesteps: expected int, got str"),
    (_train(total_timesteps=0), [],
     "config.total_timesteps: expected an integer in [1, 10000000000], got 0"),
    (_train(), ["--timesteps", "-5"],
     "config.total_timesteps: expected an integer in [1, 10000000000], got -5"),
    (_train(seed=-1), [], "config.seed: expected an integer >= 0, got -1"),
    (_train(name="../../x"), [], "config.name: expected the name of a folder in models/"),
    (_train(env_kwargs={"colour": 1}), [], "config.env_kwargs: BounceEnv() got an unexpected"),
    (_train(hyperparams={"n_steps": 0}), [],
     "config.hyperparams.n_steps: expected an integer in [1, 1000000], got 0"),
    (_train(hyperparams={"batch_size": 1}), [], "config.hyperparams: "),  # SB3's own check
    (_train(hyperparams={"learning_rate": "abc"}), [],
     "config.hyperparams.learning_rate: expected a number, got 'abc'"),
    (_train(hyperparams={"colour": 1}), [], "config.hyperparams.colour: not a hyperparameter"),
    (_train(algo="dqn", env_kwargs={"action_type": "continuous"}, hyperparams={}), [],
     "config.algo: dqn needs discrete actions"),
    (_train(), ["--resume"], "config.resume: nothing to resume: "),
    (_train(seeds=[0, 10000]), [], "config.seeds: seed 10000 with n_envs 1 would seed envs up "
                                   "to 10000"),
    (_train(n_envs=3, seeds=[9998]), [], "config.seeds: seed 9998 with n_envs 3 would seed "
                                         "envs up to 10000; training env seeds must stay below "
                                         "10000"),
    (_train(seed=0, seeds=[1]), [], "config.seeds: give either seed"),
    (_train(seeds=[1, 1]), [], "config.seeds: expected a non-empty list of distinct integers"),
    (_train(n_stack=0), [], "config.n_stack: expected an integer in [1, 100], got 0"),
    (_train(normalize={"norm_obs": 1}), [], "config.normalize.norm_obs: expected true or false"),
    (_train(normalize={"clip": 1}), [], "config.normalize: unknown keys ['clip']"),
    (_train(variant="Stack 4"), [], "config.variant: expected lower-case letters and digits"),
    (_train(hyperparams={"learning_rate": "lin_x"}), [],
     "config.hyperparams.learning_rate: expected lin_<number>, got 'lin_x'"),
    (_train(hyperparams={"n_epochs": "lin_1"}), [],
     "config.hyperparams.n_epochs: a lin_ schedule is allowed only for"),
    (_train(hyperparams={"policy_kwargs": {"activation_fn": "sigmoid"}}), [],
     "config.hyperparams.policy_kwargs.activation_fn: expected one of"),
    (_train(hyperparams_file="missing.yaml"), [], "config.hyperparams_file: file '"),
    (_train(hyperparams_file="hp.yaml"), [], "config.hyperparams_file: "),
    (_train(algo="dqn", hyperparams_file="hp.yaml"), [],
     "config.hyperparams_file: bounce_gym/BounceNavigation-v0 names policy 'MlpLstmPolicy', but "
     "dqn trains 'MlpPolicy'"),
    (_train(models="FILE/x"), [], "config.models: cannot write into"),
])
def test_train_reports_each_mistake_in_one_line(tmp_path, capsys, monkeypatch, config, extra,
                                                message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "FILE").write_text("not a folder")
    _write(tmp_path / "hp.yaml", {"bounce_gym/BounceNavigation-v0": {"policy": "MlpLstmPolicy"}}
           if isinstance(config, dict) and config.get("algo") == "dqn"
           else {"bounce_gym/Bounce-v0": {}})
    if config is not None:
        _write(tmp_path / "t.yaml", config)
    line = _one_error(capsys, ["train", "t.yaml", "--no-progress", *extra])
    assert line.startswith(f"error: {message}")
    assert not (tmp_path / "models").exists()  # nothing written, not even an empty folder


@pytest.mark.skipif(__import__("importlib").util.find_spec("tensorboard") is not None,
                    reason="tensorboard is installed")
def test_tensorboard_logs_name_the_extra_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _write(tmp_path / "t.yaml", _train(tensorboard=True))
    line = _one_error(capsys, ["train", "t.yaml", "--no-progress"])
    assert line == ("error: config.tensorboard: needs the tensorboard package "
                    "(pip install -e .[tensorboard]), or set tensorboard: false")
