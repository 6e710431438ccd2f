"""Every user mistake in `bounce-gym evaluate|train` is one line ``error: <field>: ...`` on
stderr and exit status 2, reported before any long work."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

from bounce_gym_experiments.cli import main  # noqa: E402

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
     "config.experiments[1].seeds: evaluation seeds must not overlap the training seeds "
     "[0, 9000) (baselines.seeds), got [3]"),
    (_experiment(seeds={"start": 9_950, "count": 200}),
     "config.experiments[1].seeds: evaluation seeds must not overlap the tuning seeds "
     "[9000, 10000) (baselines.seeds), got start 9950, count 200"),
    (_experiment(max_steps=7, horizon_reason=None),
     "config.experiments[1].max_steps: 7 differs from the horizon 200 that "
     "bounce_gym/BounceNavigation-v0 registers"),
    (_experiment(policies=["rl"], name="../x"),
     "config.experiments[1].name: expected a name for the plot files (one path component), got "
     "'../x': it contains '/'"),
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


def test_evaluate_refuses_a_broken_model_before_running(tmp_path, capsys):
    (tmp_path / "models" / "a").mkdir(parents=True)
    (tmp_path / "models" / "a" / "ppo_seed0.zip").write_bytes(b"PK")
    config = {"output": str(tmp_path / "runs"), "models": str(tmp_path / "models"),
              "experiments": [_experiment(policies=["random", "rl"])]}
    line = _one_error(capsys, ["evaluate", str(_write(tmp_path / "c.yaml", config))])
    assert "ppo_seed0.zip: not a readable Stable-Baselines3 model file" in line


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
    (_train(seeds=[0, 9000]), [], "config.seeds: seed 9000 with n_envs 1 would seed envs up "
                                  "to 9000"),
    (_train(n_envs=3, seeds=[8998]), [], "config.seeds: seed 8998 with n_envs 3 would seed "
                                         "envs up to 9000; training env seeds must stay below "
                                         "9000, where the tuning seeds start (baselines.seeds)"),
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


def test_tensorboard_logs_name_the_extra_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, "tensorboard", None)  # as if not installed
    _write(tmp_path / "t.yaml", _train(tensorboard=True))
    line = _one_error(capsys, ["train", "t.yaml", "--no-progress"])
    assert line == ("error: config.tensorboard: true needs the 'tensorboard' extra: "
                    "pip install 'bounce-gym[tensorboard]'")
    assert not (tmp_path / "models").exists()


# -- hostile documents, numbers and Ray addresses (issue 22) -----------------------------------


def _laughs(indent: int) -> str:
    """A YAML block list, ``indent`` spaces in: ten levels of ten aliases each, 10**10 nodes
    once expanded, a few hundred bytes as written."""
    return "".join(f"{' ' * indent}- &{chr(97 + i)} [{', '.join([f'*{chr(96 + i)}'] * 10)}]\n"
                   if i else f"{' ' * indent}- &a [{', '.join(['x'] * 10)}]\n"
                   for i in range(10))


def _evaluate_text(tmp_path: Path, text: str | bytes) -> list[str]:
    path = tmp_path / "c.yaml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return ["evaluate", str(path), "--no-progress"]


def _experiment_yaml(tmp_path: Path, **overrides) -> str:
    return yaml.safe_dump({"output": str(tmp_path / "runs"),
                           "experiments": [_experiment(**overrides)]})


@pytest.mark.timeout(120)  # a hang guard only
@pytest.mark.parametrize(("text", "message"), [
    ("experiments: " + "[" * 5000 + "]" * 5000,
     "config: {path}: lists and mappings nest more than 32 deep; at most 32 are allowed"),
    ("name: x\nexperiments:\n" + "".join("  " * k + "-\n" for k in range(1, 1500)),
     "config: {path}: lists and mappings nest more than 32 deep"),
    ("name: " + "x" * 5 * 2**20, "config: {path}: 5242886 bytes; at most 4194304 are allowed"),
    ("name: caf\xe9\n".encode("latin-1"), "config: {path}: not UTF-8 text: byte 0xe9 at offset 9"),
    ("experiments:\n- name: a\n  env: bounce_gym/BounceNavigation-v0\n  env_kwargs:\n"
     f"    world: square\n    x:\n{_laughs(6)}",
     "config: {path}: more than 120000 nodes with its aliases expanded"),
    ("experiments:\n- name: a\n  env: bounce_gym/BounceNavigation-v0\n  visibility:\n"
     f"    x:\n{_laughs(6)}", "config: {path}: more than 120000 nodes"),
    ("experiments: &e [*e]\n", "config: {path}: the alias *e at line 1, column 18 names no "
                               "anchor before it, or a node that contains it"),
    ("experiments: []\nexperiments: []\n", "config: {path}: not valid YAML: found duplicate key "
                                           "'experiments' at line 2, column 1"),
    ("yes: 1\n", "config: {path}: not valid YAML: found a key that is not a string: True"),
    ("name: !!python/object/apply:os.system [echo hi]\n",
     "config: {path}: not valid YAML: could not determine a constructor for the tag"),
])
def test_a_hostile_configuration_file_is_one_line(tmp_path, capsys, text, message):
    argv = _evaluate_text(tmp_path, text)
    assert _one_error(capsys, argv).startswith(f"error: {message.format(path=argv[1])}")
    assert not (tmp_path / "runs").exists()


def test_a_control_character_in_a_name_stops_the_evaluation_before_it_runs(tmp_path, capsys):
    # used to run the evaluation, then end in a traceback writing the run folder
    argv = _evaluate_text(tmp_path, _experiment_yaml(tmp_path).replace("name: a", 'name: "a\\0b"'))
    line = _one_error(capsys, argv)
    assert line.startswith(f"error: config: {argv[1]}: control character U+0000 in the string "
                           "'a\\x00b'")
    assert not (tmp_path / "runs").exists()


@pytest.mark.timeout(120)  # a hang guard only: the checks are linear in the number of seeds
@pytest.mark.parametrize(("seeds", "message"), [
    ({"start": 10_000, "count": 10_000_000_000},  # used to end in MemoryError
     "seeds.count: expected an integer in [1, 100000], got 10000000000"),
    ({"start": 2**32 - 5, "count": 10}, "seeds.count: expected an integer in [1, 5], got 10"),
    ({"start": 2**40, "count": 1}, "seeds.start: expected an integer in [10000, 4294967295]"),
    ([*range(10_000, 109_999), 10_000],  # 100,000 seeds, one twice: used to run for minutes
     "seeds: every seed once (an episode counts once), repeated: [10000]"),
    (list(range(10_000, 110_001)), "seeds: at most 100000 seeds, got 100001"),
    ([10_000, 2**32], "seeds: evaluation seeds must be <= 4294967295, got [4294967296]"),
])
def test_evaluation_seeds_are_checked_in_linear_time(tmp_path, capsys, seeds, message):
    argv = _evaluate_text(tmp_path, _experiment_yaml(tmp_path, seeds=seeds))
    assert _one_error(capsys, argv).startswith(f"error: config.experiments[0].{message}")


@pytest.mark.timeout(60)  # a hang guard only: Ray used to retry the address for minutes
def test_max_steps_and_the_executor_block_have_ranges(tmp_path, capsys):
    argv = _evaluate_text(tmp_path, _experiment_yaml(tmp_path, max_steps=10**9))
    assert _one_error(capsys, argv) == ("error: config.experiments[0].max_steps: expected an "
                                        "integer in [1, 1000000], got 1000000000")
    config = yaml.safe_load(_experiment_yaml(tmp_path))
    for block, message in (({"workers": 10**6}, "config.executor.workers: expected an integer "
                                                "in [1, 1024], got 1000000"),
                           ({"kind": "ray", "address": "256.1.1.1:1"},
                            "config.executor.address: expected a Ray address")):
        argv = _evaluate_text(tmp_path, yaml.safe_dump({**config, "executor": block}))
        assert _one_error(capsys, argv).startswith(f"error: {message}")


def _closed_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.mark.timeout(60)  # a hang guard only: `--address garbage:1` used to hang
@pytest.mark.parametrize(("address", "message"), [
    ("garbage:1", "--address: cannot reach a Ray cluster at 'garbage:1': "),
    ("ray://256.1.1.1:1", "--address: expected a Ray address (auto, host:port or ray://host:port; "
                          "a host name or IP address, a port in 1..65535), got "
                          "'ray://256.1.1.1:1'"),
    ("host:0", "--address: expected a Ray address"),
    ("host:65536", "--address: expected a Ray address"),
    ("local", "--address: expected a Ray address"),
    ("auto", "--address: auto: no running Ray cluster found (RAY_ADDRESS names none and "),
    ("127.0.0.1:PORT", "--address: cannot reach a Ray cluster at '127.0.0.1:PORT': Connection "
                       "refused"),
])
def test_a_ray_address_is_checked_before_ray_connects(tmp_path, capsys, monkeypatch, address,
                                                      message):
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path))  # no cluster recorded there
    port = str(_closed_port())
    argv = [*_evaluate_text(tmp_path, _experiment_yaml(tmp_path)), "--executor", "ray",
            "--address", address.replace("PORT", port)]
    assert _one_error(capsys, argv).startswith(f"error: {message.replace('PORT', port)}")


@pytest.mark.parametrize(("config", "message"), [
    (_train(hyperparams={"gamma": 5}),  # used to train NaNs, three times
     "config.hyperparams.gamma: expected a number in (0, 1], got 5"),
    (_train(torch_threads=1_000_000),  # used to end in MemoryError
     f"config.torch_threads: expected an integer in [1, {4 * (__import__('os').cpu_count() or 1)}"
     "], got 1000000"),
    (_train(hyperparams={"gae_lambda": 1.5}), "config.hyperparams.gae_lambda: expected a number "
                                              "in [0, 1], got 1.5"),
    (_train(hyperparams={"learning_rate": 0}), "config.hyperparams.learning_rate: expected a "
                                               "number > 0, got 0.0"),
    ("name: nav\nenv: bounce_gym/BounceNavigation-v0\nalgo: ppo\ntotal_timesteps: 64\n"
     "hyperparams: {learning_rate: .nan}\n",
     "config.hyperparams.learning_rate: expected a finite number, got nan"),
    ("name: nav\nenv: bounce_gym/BounceNavigation-v0\nalgo: ppo\ntotal_timesteps: 64\n"
     "hyperparams: {policy_kwargs: {net_arch: {pi: [.inf]}}}\n",
     "config.hyperparams.policy_kwargs.net_arch.pi[0]: expected a finite number, got inf"),
    (_train(hyperparams={"learning_rate": "lin_1e999"}),
     "config.hyperparams.learning_rate (the start of its lin_ schedule): expected a finite "
     "number, got inf"),
    (_train(hyperparams={"clip_range": -0.2}), "config.hyperparams.clip_range: expected a "
                                               "number > 0"),
    (_train(hyperparams={"ent_coef": -1}), "config.hyperparams.ent_coef: expected a number >= 0"),
    (_train(hyperparams={"max_grad_norm": 0}), "config.hyperparams.max_grad_norm: expected a "
                                               "number > 0"),
    (_train(hyperparams={"n_epochs": 10**9}), "config.hyperparams.n_epochs: expected an integer "
                                              "in [1, 1000]"),
    (_train(hyperparams={"batch_size": 2.5}), "config.hyperparams.batch_size: expected an "
                                              "integer in [1, 1000000], got 2.5"),
    (_train(algo="dqn", n_envs=1, hyperparams={"buffer_size": 10**12}),
     "config.hyperparams.buffer_size: expected an integer in [1, 10000000]"),
    (_train(algo="dqn", n_envs=1, hyperparams={"exploration_final_eps": 2}),
     "config.hyperparams.exploration_final_eps: expected a number in [0, 1], got 2"),
    (_train(n_envs=1000, hyperparams={"n_steps": 100_000}),
     "config.hyperparams.n_steps: n_steps x n_envs is a rollout of 100000000 transitions"),
    (_train(hyperparams={"policy_kwargs": {"net_arch": [10**9]}}),
     "config.hyperparams.policy_kwargs.net_arch[0]: expected an integer in [1, 4096]"),
    (_train(hyperparams={"policy_kwargs": {"net_arch": [8] * 17}}),
     "config.hyperparams.policy_kwargs.net_arch: expected a list of at most 16 layer sizes"),
    (_train(hyperparams={"policy_kwargs": {"net_arch": {"actor": [8]}}}),
     "config.hyperparams.policy_kwargs.net_arch: unknown keys ['actor']"),
    (_train(algo="recurrentppo", hyperparams={"policy_kwargs": {"lstm_hidden_size": 10**6}}),
     "config.hyperparams.policy_kwargs.lstm_hidden_size: expected an integer in [1, 4096]"),
    (_train(total_timesteps=10**11), "config.total_timesteps: expected an integer in "
                                     "[1, 10000000000], got 100000000000"),
    (_train(n_envs=10**6), "config.n_envs: expected an integer in [1, 1024], got 1000000"),
    (_train(checkpoint_every=-1), "config.checkpoint_every: expected an integer in "
                                  "[0, 10000000000], got -1"),
    (_train(normalize={"clip_obs": float("inf")}), "config.normalize.clip_obs: expected a "
                                                   "finite number, got inf"),
    (_train(normalize={"clip_reward": 0}), "config.normalize.clip_reward: expected a number > 0"),
])
def test_every_training_number_has_a_range(tmp_path, capsys, monkeypatch, config, message):
    monkeypatch.chdir(tmp_path)
    _write(tmp_path / "t.yaml", config)
    line = _one_error(capsys, ["train", "t.yaml", "--no-progress"])
    assert line.startswith(f"error: {message}")
    assert not (tmp_path / "models").exists()


def test_a_hostile_hyperparameter_file_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "hp.yaml").write_text(f"bounce_gym/BounceNavigation-v0:\n  x:\n{_laughs(2)}",
                                      encoding="utf-8")
    _write(tmp_path / "t.yaml", _train(hyperparams_file="hp.yaml"))
    assert _one_error(capsys, ["train", "t.yaml"]).startswith(
        "error: config.hyperparams_file: hp.yaml: more than 120000 nodes")


def _tune(tmp_path: Path, space: str, *flags: str) -> list[str]:
    _write(tmp_path / "t.yaml", _train(models=str(tmp_path / "models")))
    (tmp_path / "space.yaml").write_text(space, encoding="utf-8")
    return ["tune", str(tmp_path / "t.yaml"), "--space", str(tmp_path / "space.yaml"),
            "--no-progress", *flags]


@pytest.mark.timeout(120)  # a hang guard only
@pytest.mark.parametrize(("space", "flags", "message"), [
    ("n_epochs: {randint: [0, 1000000000000000000000000000000]}", [],
     "search.n_epochs.randint: expected [low, high], integers in [-9223372036854775808, "
     "9223372036854775807] with low < high"),
    ("n_epochs: {randint: [3, 3]}", [], "search.n_epochs.randint: expected [low, high]"),
    ("n_epochs: {randint: [0, 10]}", [],
     "search.n_epochs.randint[0]: expected an integer in [1, 1000], got 0"),
    ("gamma: {uniform: [0.9, 1.5]}", [],
     "search.gamma.uniform[1]: expected a number in (0, 1], got 1.5"),
    ("learning_rate: {loguniform: [1.0e-5, .inf]}", [],
     "search.learning_rate.loguniform: expected [low, high], numbers with 0 < low < high"),
    ("n_epochs: {uniform: [1, 3]}", [],
     "search.n_epochs.uniform[0]: expected an integer in [1, 1000], got 1.0"),
    ("gamma: {choice: [0.9, 2]}", [], "search.gamma.choice[1]: expected a number in (0, 1]"),
    ("batch_size: {choice: [" + ", ".join(["64"] * 10_001) + "]}", [],
     "search.batch_size.choice: expected a list of 1 to 10000 values, got 10001 values"),
    (f"policy_kwargs:\n  choice:\n{_laughs(2)}", [], "search: {space}: more than 120000 "
                                                    "nodes with its aliases expanded"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--trials", "1000000000"],
     "--trials: expected an integer in [1, 10000], got 1000000000"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--seed", "-1"],
     "--seed: expected an integer in [0, 4294967295], got -1"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--workers", "0"],
     "--workers: expected an integer in [1, 1024], got 0"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--metric", "bogus"],
     "--metric: expected one of ['return', 'success'], got 'bogus'"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--scheduler", "bogus"],
     "--scheduler: expected one of ['fifo', 'asha'], got 'bogus'"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--address", "ray://256.1.1.1:1"],
     "--address: expected a Ray address"),
    ("gamma: {uniform: [0.9, 0.99]}", ["--address", "garbage:1"],
     "--address: cannot reach a Ray cluster at 'garbage:1'"),
])
def test_tune_checks_everything_before_it_prepares_a_trial(tmp_path, capsys, monkeypatch, space,
                                                            flags, message):
    import bounce_gym_experiments.search

    def prepared_a_trial(*args, **kwargs):
        raise AssertionError("a trial was prepared before the mistake was found")

    monkeypatch.setattr(bounce_gym_experiments.search, "prepare", prepared_a_trial)
    line = _one_error(capsys, _tune(tmp_path, space, *flags))
    assert line.startswith(f"error: {message.format(space=tmp_path / 'space.yaml')}")


@pytest.mark.parametrize(("argv", "message"), [
    (["tune", "t.yaml", "--trials", "many"], "error: argument --trials: invalid int value: "
                                             "'many' (see bounce-gym tune --help)"),
    (["evaluate", "--colour"], "error: unrecognized arguments: --colour (see bounce-gym evaluate "
                                "--help)"),
    (["train"], "error: the following arguments are required: config (see bounce-gym train "
                "--help)"),
])
def test_a_usage_mistake_is_one_line(capsys, argv, message):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert capsys.readouterr().err == message + "\n"


HEAVY = ("torch", "stable_baselines3", "sb3_contrib", "ray", "xarray", "netCDF4", "matplotlib",
         "scipy", "shapely", "pymunk", "pygame")


@pytest.mark.parametrize(("argv", "text"), [
    (["evaluate", "c.yaml"], "name: x\n"),
    (["evaluate", "c.yaml"], "experiments: [{name: a, colour: 1}]\n"),
    (["evaluate", "c.yaml"], "experiments: [unclosed\n"),
    (["train", "c.yaml"], "name: x\nenv: bounce_gym/BounceNavigation-v0\nalgo: ppo\ncolour: 1\n"),
    (["train", "c.yaml"], "name: x\nenv: bounce_gym/BounceNavigation-v0\nalgo: ppo\n"
                          "total_timesteps: 64\nhyperparams: {gamma: 5}\n"),
    (["tune", "c.yaml", "--metric", "bogus"], "name: x\n"),
    (["tune", "c.yaml", "--trials", "0"], "name: x\nenv: bounce_gym/BounceNavigation-v0\n"
                                          "algo: ppo\ntotal_timesteps: 64\n"),
])
def test_a_configuration_error_comes_before_any_heavy_import(tmp_path, argv, text):
    (tmp_path / "c.yaml").write_text(text, encoding="utf-8")
    code = ("import sys\nfrom bounce_gym_experiments.cli import main\nstatus = main(sys.argv[1:])\n"
            f"print(status, sorted(set({HEAVY!r}) & set(sys.modules)))\n")
    done = __import__("subprocess").run([sys.executable, "-c", code, *argv], cwd=tmp_path,
                                        capture_output=True, text=True, timeout=300,
                                        env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.stdout == "2 []\n", done.stderr
    errors = done.stderr.splitlines()
    assert len(errors) == 1 and errors[0].startswith("error: "), done.stderr


def test_evaluate_runs_only_the_experiments_named(tmp_path, capsys):
    """``--experiments`` keeps the configuration's order and leaves the others out; an unknown
    name is one line that suggests the nearest, before anything runs."""
    config = _write(tmp_path / "c.yaml", {
        "name": "pick", "output": str(tmp_path / "runs"),
        "experiments": [_experiment(name="first"), _experiment(name="second")]})
    line = _one_error(capsys, ["evaluate", str(config), "--experiments", "secnd"])
    assert line == ("error: --experiments: no experiment named 'secnd' in the configuration; "
                    "did you mean 'second'?")
    assert not (tmp_path / "runs").exists()
    assert main(["evaluate", str(config), "--experiments", "second", "--workers", "1",
                 "--no-progress"]) == 0
    (run,) = (tmp_path / "runs").iterdir()
    results = json.loads((run / "results.json").read_text(encoding="utf-8"))
    assert {row["experiment"] for row in results["summary"]} == {"second"}


FAST_CHILD = """
import sys
from bounce_gym_experiments.cli import main
status = main(["evaluate", sys.argv[1], "--no-progress"])
heavy = sorted(m for m in ("bounce_gym_experiments.registry", "bounce_gym_experiments.runner",
                           "scipy.stats", "scipy.ndimage", "networkx", "torch") if m in sys.modules)
print(status, *heavy)
"""


@pytest.mark.parametrize("env_kwargs", [{**NAV, "colour": 1}, {**NAV, "step_length": 1e12},
                                        {"world": "square", "task_kwargs": {"colour": 1}}])
def test_a_bad_env_argument_is_reported_before_the_heavy_imports(tmp_path, env_kwargs):
    """Issue 36, item 6: an env argument's error took 4.6-8.1 s against 1.0-2.5 s for a
    document's, since the experiment families (SciPy's statistics, the drifter baselines) and
    the runner were imported before the env was ever built. Now the env is built while the
    configuration is checked, before any of them (and building it needs neither
    scipy.ndimage nor networkx)."""
    config = _write(tmp_path / "c.yaml", {"name": "run", "output": str(tmp_path / "out"),
                                          "experiments": [_experiment(env_kwargs=env_kwargs)]})
    done = subprocess.run([sys.executable, "-c", FAST_CHILD, str(config)], capture_output=True,
                          text=True, cwd=ROOT, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.stdout.split() == ["2"], (done.stdout, done.stderr)
    assert len(done.stderr.splitlines()) == 1
    assert done.stderr.startswith("error: config.experiments[0].env_kwargs: "), done.stderr


@pytest.mark.parametrize("command", ["train", "evaluate"])
def test_an_unknown_env_id_lists_every_registered_id(tmp_path, capsys, command):
    """The list comes from the registry (`bounce_gym.envs.registration.ENV_IDS`): training's
    once left out ``bounce_gym/Patrol-v0``."""
    from bounce_gym.envs.registration import ENV_IDS

    env = "bounce_gym/Nothing-v0"
    config = ({"name": "x", "experiments": [_experiment(env=env)]} if command == "evaluate"
              else {"name": "x", "env": env, "algo": "ppo", "total_timesteps": 64})
    line = _one_error(capsys, [command, str(_write(tmp_path / "c.yaml", config))])
    assert line.endswith(f"unknown environment id {env!r}; registered: {list(ENV_IDS)}")
    assert "bounce_gym/Patrol-v0" in ENV_IDS
