"""Training configurations: the shipped configs and rl-zoo style hyperparameter files are
valid, the file merges under the configuration, and schedules and activations map to SB3's."""

from pathlib import Path

import pytest
import yaml

pytest.importorskip("stable_baselines3")

from baselines.rl.model_files import ALGOS, JAX_ALGOS, MARL_ALGOS  # noqa: E402
from baselines.rl.train_config import (  # noqa: E402
    algo_class,
    algo_kwargs,
    check_hyperparams,
    policy_name,
    validate_train_config,
)
from baselines.rl.train_env import make_train_env  # noqa: E402
from baselines.seeds import TRAINING_SEEDS  # noqa: E402

CONFIGS = Path(__file__).parents[3] / "configs"
TRAIN_CONFIGS = sorted(CONFIGS.glob("train_*.yaml"))
HYPERPARAMS = sorted((CONFIGS / "hyperparams").glob("*.yaml"))
#: the smallest budget per seed of a shipped configuration
LEAST_BUDGET = 10_000


@pytest.mark.parametrize("path", TRAIN_CONFIGS, ids=[p.name for p in TRAIN_CONFIGS])
def test_shipped_training_configs_build_their_model(path):
    config = validate_train_config(yaml.safe_load(path.read_text()), path.parent)
    assert config["total_timesteps"] >= LEAST_BUDGET
    assert len(config["seeds"]) >= 1
    assert max(config["seeds"]) + config["n_envs"] <= TRAINING_SEEDS.stop
    if config["algo"] in JAX_ALGOS:  # the JAX learner, built (its checks) but not compiled
        pytest.importorskip("jax")
        from baselines.rl.jaxrl.runner import learner

        assert learner(config).iterations >= 1
        return
    if config["algo"] in MARL_ALGOS:  # the teams and the networks, built
        from baselines.rl.marl.ppo import Learner

        assert Learner(config, config["seeds"][0], ()).iterations >= 1
        return
    cls = algo_class(config["algo"])
    check_hyperparams(cls, config["hyperparams"])
    env = make_train_env({**config, "n_envs": min(config["n_envs"], 2),
                          "vec_env": "sync" if config["vec_env"] == "subproc" else
                          config["vec_env"]})
    model = cls(policy_name(config["algo"], env.observation_space), env, device="cpu",
                **algo_kwargs(config["hyperparams"]))
    assert model.policy is not None
    env.close()


@pytest.mark.parametrize("path", HYPERPARAMS, ids=[p.name for p in HYPERPARAMS])
def test_every_hyperparameter_entry_states_a_budget_and_real_hyperparameters(path):
    algo = path.stem
    assert algo in ALGOS
    for key, entry in yaml.safe_load(path.read_text()).items():
        assert entry["n_timesteps"] >= 10_000, key  # the stated training budget
        env_id, _, role = key.partition(":")  # <env>:<role> for a side of the patrol game
        config = validate_train_config({"name": "x", "env": env_id, "algo": algo,
                                        "hyperparams_file": str(path),
                                        **({"role": role} if role else {})})
        assert config["total_timesteps"] == entry["n_timesteps"]
        if algo not in MARL_ALGOS:  # theirs are checked by validate_train_config
            check_hyperparams(algo_class(algo), config["hyperparams"])


def test_the_configuration_wins_over_its_hyperparameter_file(tmp_path):
    (tmp_path / "hp.yaml").write_text(
        "bounce_gym/Bounce-v0:\n  n_timesteps: !!float 2e5\n  n_envs: 8\n  frame_stack: 4\n"
        "  normalize: true\n  n_steps: 64\n  gamma: 0.9\n  policy: MlpPolicy\n")
    base = {"name": "x", "env": "bounce_gym/Bounce-v0", "algo": "ppo",
            "hyperparams_file": "hp.yaml"}
    config = validate_train_config(base, tmp_path)
    assert (config["total_timesteps"], config["n_envs"], config["n_stack"]) == (200_000, 8, 4)
    assert config["normalize"]["norm_obs"] and config["normalize"]["norm_reward"]
    assert config["hyperparams"] == {"n_steps": 64, "gamma": 0.9}
    assert config["hyperparams_file"] == str(tmp_path / "hp.yaml")
    ours = validate_train_config({**base, "total_timesteps": 10, "n_envs": 2, "n_stack": 1,
                                  "normalize": False, "hyperparams": {"gamma": 0.5}}, tmp_path)
    assert (ours["total_timesteps"], ours["n_envs"], ours["n_stack"]) == (10, 2, 1)
    assert ours["normalize"] is None and ours["hyperparams"] == {"n_steps": 64, "gamma": 0.5}


def test_linear_schedules_and_activation_names():
    from torch import nn

    kwargs = algo_kwargs({"learning_rate": "lin_1e-3", "clip_range": 0.2,
                          "policy_kwargs": {"activation_fn": "relu", "net_arch": [8]}})
    assert kwargs["learning_rate"](1.0) == pytest.approx(1e-3)
    assert kwargs["learning_rate"](0.25) == pytest.approx(2.5e-4)
    assert kwargs["clip_range"] == 0.2
    assert kwargs["policy_kwargs"] == {"activation_fn": nn.ReLU, "net_arch": [8]}


def test_every_ranged_hyperparameter_takes_its_bounds_and_refuses_beyond_them():
    from baselines.rl.train_config import HYPERPARAM_RANGES, check_range
    from bounce_gym.errors import ConfigError

    for key, (whole, least, most, excluded, nullable) in HYPERPARAM_RANGES.items():
        inside = [least + (1 if whole else 0.5) if excluded else least]
        if most is not None:
            inside.append(most)
        for value in inside:
            check_range(f"h.{key}", key, value)
        outside = [least if excluded else least - 1, float("nan"), float("inf"), "x", True]
        if most is not None:
            outside.append(most + 1)
        if whole:
            outside.append(float(inside[0]))  # an integer is not a float
        if not nullable:
            outside.append(None)
        for value in outside:
            with pytest.raises(ConfigError, match=rf"^h\.{key}: expected a"):
                check_range(f"h.{key}", key, value)
    check_range("h.colour", "colour", float("nan"))  # no range of its own: SB3 decides


def test_a_schedule_is_checked_on_its_start():
    from baselines.rl.train_config import check_range
    from bounce_gym.errors import ConfigError

    check_range("h.learning_rate", "learning_rate", "lin_3e-4")
    with pytest.raises(ConfigError, match=r"h.clip_range \(the start of its lin_ schedule\): "
                                          r"expected a number > 0, got 0.0"):
        check_range("h.clip_range", "clip_range", "lin_0")


def test_numbers_anywhere_in_the_hyperparameters_are_finite():
    from bounce_gym.errors import ConfigError

    base = {"name": "x", "env": "bounce_gym/BounceNavigation-v0", "algo": "ppo",
            "total_timesteps": 64}
    for hyperparams, field in (({"target_kl": float("nan")}, "target_kl"),
                               ({"policy_kwargs": {"net_arch": {"vf": [float("inf")]}}},
                                r"policy_kwargs.net_arch.vf\[0\]"),
                               ({"normalize_advantage": True, "x": [1, [float("-inf")]]},
                                r"x\[1\]\[0\]")):
        with pytest.raises(ConfigError, match=rf"^config.hyperparams.{field}: expected a finite "
                                              "number"):
            validate_train_config({**base, "hyperparams": hyperparams})
    assert validate_train_config({**base, "hyperparams": {"target_kl": None, "clip_range_vf":
                                                          None}})["hyperparams"]["target_kl"] is None


def test_the_replay_buffer_is_named_and_its_arguments_checked():
    from bounce_gym.errors import ConfigError

    base = {"name": "x", "env": "bounce_gym/BounceNavigation-v1", "algo": "dqn",
            "total_timesteps": 64}
    her = {"replay_buffer_class": "HerReplayBuffer"}
    config = validate_train_config({**base, "hyperparams": {
        **her, "replay_buffer_kwargs": {"n_sampled_goal": 4, "goal_selection_strategy": "future"}}})
    assert algo_kwargs(config["hyperparams"])["replay_buffer_class"].__name__ == "HerReplayBuffer"
    for hyperparams, message in (
            ({"replay_buffer_class": "builtins.eval"}, r"replay_buffer_class: expected one of"),
            ({"replay_buffer_kwargs": {"n_sampled_goal": 4}}, r"only with replay_buffer_class"),
            ({**her, "replay_buffer_kwargs": {"env": "x"}}, r"kwargs.env: not an argument"),
            ({**her, "replay_buffer_kwargs": {"n_sampled_goal": 0}}, r"n_sampled_goal"),
            ({**her, "replay_buffer_kwargs": {"goal_selection_strategy": "past"}},
             r"goal_selection_strategy: expected one of"),
            ({**her, "replay_buffer_kwargs": {"copy_info_dict": 1}}, r"expected true or false")):
        with pytest.raises(ConfigError, match=rf"^config.hyperparams.{message}|{message}"):
            validate_train_config({**base, "hyperparams": hyperparams})
    assert policy_name("dqn", make_train_env({**config, "n_envs": 1}).observation_space) == \
        "MultiInputPolicy"
