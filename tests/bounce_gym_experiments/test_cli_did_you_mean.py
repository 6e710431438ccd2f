"""A misspelled env argument or configuration key is the package's one-line `ConfigError` with
the name it most likely stands for (``did you mean 'world'?``), from Python, Gymnasium's and
PettingZoo's ``make`` and through the CLI (exit status 2)."""

import sys
from pathlib import Path

import gymnasium as gym
import pettingzoo
import pytest
import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import bounce_gym  # noqa: E402, F401  (registers the environments)
from bounce_gym.errors import ConfigError  # noqa: E402
from bounce_gym.validate import did_you_mean  # noqa: E402
from bounce_gym_experiments.cli import main  # noqa: E402

NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}


@pytest.mark.parametrize(("env_id", "kwargs", "hint"), [
    ("bounce_gym/Bounce-v0", {"worlds": "x"}, "(did you mean 'world'?)"),
    ("bounce_gym/BounceNavigation-v1", {"histroy": 2}, "(did you mean 'history'?)"),
    ("bounce_gym/Drifter-v0", {"flows": "x"}, "(did you mean 'flow'?)"),
])
def test_gymnasium_make_names_the_argument_meant(env_id, kwargs, hint):
    with pytest.raises(ConfigError) as error:
        gym.make(env_id, **kwargs)
    message = str(error.value)
    assert f"got an unexpected keyword argument '{next(iter(kwargs))}' {hint}" in message
    assert "\n" not in message


@pytest.mark.parametrize(("env_id", "hint"), [
    ("bounce_gym/MultiBounce-v0", "(did you mean 'world'?)"),
    ("bounce_gym/Patrol-v0", "(did you mean 'world'?)"),
])
def test_pettingzoo_make_names_the_argument_meant(env_id, hint):
    with pytest.raises(ConfigError, match=r"unexpected keyword argument 'worlds' \(did you mean "
                                          r"'world'\?\)$"):
        pettingzoo.make("parallel", env_id, worlds="x")


def test_a_task_argument_names_the_one_meant():
    with pytest.raises(ConfigError, match=r"^task_kwargs for 'navigation': NavigationTask.__init__"
                                          r"\(\) got an unexpected keyword argument 'rewrd' "
                                          r"\(did you mean 'reward'\?\)"):
        gym.make("bounce_gym/BounceNavigation-v0", task_kwargs={"rewrd": "sparse"})


def test_an_argument_close_to_none_gets_no_guess():
    with pytest.raises(ConfigError) as error:
        gym.make("bounce_gym/Bounce-v0", colour=1)
    assert "did you mean" not in str(error.value)


def test_did_you_mean_pairs_each_misspelling_with_its_name():
    assert did_you_mean(["seed"], ["seeds", "name"]) == "did you mean 'seeds'?"
    assert did_you_mean(["seed", "wrld", "colour"], ["seeds", "world"]) == \
        "did you mean 'seeds' for 'seed', 'world' for 'wrld'?"
    assert did_you_mean(["colour"], ["seeds", "world"]) == ""


def _one_error(capsys, tmp_path, argv: list[str], config: dict) -> str:
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    assert main([*argv, str(path), "--no-progress"]) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), captured.err
    assert captured.out == ""
    return lines[0]


def _experiment(**overrides) -> dict:
    return {"name": "a", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
            "seeds": [10_000], "max_steps": 5, "horizon_reason": "a quick test",
            "policies": ["random"], **overrides}


def _training(**overrides) -> dict:
    return {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
            "algo": "ppo", "total_timesteps": 64, "n_envs": 1,
            "hyperparams": {"n_steps": 32, "batch_size": 32}, **overrides}


def _without(mapping: dict, key: str) -> dict:
    return {k: v for k, v in mapping.items() if k != key}


@pytest.mark.parametrize(("config", "message"), [
    ({"outputs": "runs", "experiments": [_experiment()]},
     "error: config: unknown keys ['outputs'] (did you mean 'output'?); allowed are "),
    ({"experiments": [_without(_experiment(seed=[10_000]), "seeds")]},
     "error: config.experiments[0]: unknown keys ['seed'] (did you mean 'seeds'?); allowed are "),
    ({"experiments": [_experiment(env_kwargs={**NAV, "worlds": "square"})]},
     "error: config.experiments[0].env_kwargs: BounceEnv() got an unexpected keyword argument "
     "'worlds' (did you mean 'world'?)"),
    ({"experiments": [_experiment(env_kwargs={**NAV, "task_kwargs": {"rewrd": "sparse"}})]},
     "error: config.experiments[0].env_kwargs: task_kwargs for 'navigation': "
     "NavigationTask.__init__() got an unexpected keyword argument 'rewrd' (did you mean "
     "'reward'?)"),
])
def test_evaluate_names_the_key_meant(tmp_path, capsys, config, message):
    assert _one_error(capsys, tmp_path, ["evaluate"], config).startswith(message)


@pytest.mark.parametrize(("config", "message"), [
    (_training(seed=[1, 2]), "error: config.seed: expected int, got list (did you mean 'seeds'?)"),
    (_training(normalise=True),
     "error: config: unknown keys ['normalise'] (did you mean 'normalize'?); allowed are "),
    (_training(env_kwargs={**NAV, "worlds": "square"}),
     "error: config.env_kwargs: BounceEnv() got an unexpected keyword argument 'worlds' (did you "
     "mean 'world'?)"),
    (_training(normalize={"norm_ob": True}),
     "error: config.normalize: unknown keys ['norm_ob'] (did you mean 'norm_obs'?)"),
    (_training(hyperparams={"n_step": 32}),
     "error: config.hyperparams.n_step: not a hyperparameter of PPO (did you mean 'n_steps'?)"),
])
def test_train_names_the_key_meant(tmp_path, capsys, config, message):
    assert _one_error(capsys, tmp_path, ["train"], config).startswith(message)
