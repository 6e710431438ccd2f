"""The SB3 view of a Gymnasium vector env, and PPO training through it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

import bounce_gym  # noqa: E402,F401
from baselines.rl.train import make_train_env, train, validate_train_config  # noqa: E402
from baselines.rl.vector_vec_env import VectorToVecEnv  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402

ENV = "bounce_gym/BounceNavigation-v0"
KWARGS = {"backend": "cell", "max_episode_steps": 15}


def test_same_steps_as_dummy_vec_env_with_same_step_autoreset():
    """Seeded alike, the view and SB3's DummyVecEnv of gym.make copies agree step by step,
    terminal observations and time-limit flags included."""
    native = VectorToVecEnv(gym.make_vec(ENV, num_envs=3, vectorization_mode="vector_entry_point",
                                         **KWARGS))
    dummy = make_vec_env(ENV, n_envs=3, env_kwargs=KWARGS)
    native.seed(7)
    dummy.seed(7)
    assert np.array_equal(native.reset(), dummy.reset())
    rng = np.random.default_rng(0)
    dones = 0
    for _ in range(40):
        actions = rng.integers(0, 3, 3)
        obs, rew, done, infos = native.step(actions)
        obs2, rew2, done2, infos2 = dummy.step(actions)
        assert np.array_equal(obs, obs2) and np.array_equal(rew, rew2)
        assert np.array_equal(done, done2)
        for i in np.flatnonzero(done):
            dones += 1
            assert np.array_equal(infos[i]["terminal_observation"],
                                  infos2[i]["terminal_observation"])
            assert infos[i]["TimeLimit.truncated"] == infos2[i]["TimeLimit.truncated"]
    assert dones >= 3


def test_train_config_vec_env():
    config = {"name": "x", "env": ENV, "algo": "ppo", "total_timesteps": 10}
    assert validate_train_config(config)["vec_env"] == "native"
    assert validate_train_config({**config, "env": "bounce_gym/BounceLocalization-v0"})[
        "vec_env"] == "sync"
    with pytest.raises(ConfigError, match="vec_env"):
        validate_train_config({**config, "vec_env": "fast"})
    with pytest.raises(ConfigError, match="native"):
        validate_train_config({**config, "env": "bounce_gym/BounceLocalization-v0",
                               "vec_env": "native"})
    env = make_train_env(validate_train_config({**config, "n_envs": 2}))
    assert env.num_envs == 2
    env.close()


def test_tiny_ppo_training_through_the_native_view(tmp_path):
    config = {"name": "tiny", "env": ENV, "env_kwargs": {"backend": "cell"}, "algo": "ppo",
              "total_timesteps": 256, "n_envs": 4, "models": str(tmp_path),
              "hyperparams": {"n_steps": 32, "batch_size": 64, "n_epochs": 1}}
    (path,) = train(config, progress=False)
    assert path.is_file()


@pytest.mark.parametrize("threads", [None, 2])
def test_torch_runs_the_configured_threads_while_training(tmp_path, threads):
    """One intra-op thread unless the configuration says otherwise, while the model learns;
    the caller's setting is back afterwards."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback

    seen = []

    class Threads(BaseCallback):
        def _on_step(self) -> bool:
            seen.append(torch.get_num_threads())
            return True

    config = {"name": "x", "env": ENV, "algo": "ppo", "env_kwargs": {"backend": "cell"},
              "total_timesteps": 64, "n_envs": 2, "models": str(tmp_path),
              "hyperparams": {"n_steps": 32, "batch_size": 32, "n_epochs": 1}}
    if threads is not None:
        config["torch_threads"] = threads
    with pytest.raises(ConfigError, match="torch_threads"):
        validate_train_config({**config, "torch_threads": 0})
    before = torch.get_num_threads()
    try:
        torch.set_num_threads(3)
        train(config, progress=False, callbacks=[Threads()])
        assert torch.get_num_threads() == 3
    finally:
        torch.set_num_threads(before)
    assert seen and set(seen) == {threads or 1}
