"""The wrappers a model was trained behind (frame stack, VecNormalize) travel in its trusted
file and are applied by `SB3Policy` exactly as SB3's own VecEnv pipeline applies them."""

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.vec_env import (  # noqa: E402
    DummyVecEnv,
    VecFrameStack,
    VecNormalize,
)

import bounce_gym  # noqa: E402,F401
from baselines.rl.model_files import read_model  # noqa: E402
from baselines.rl.policies import SB3Policy  # noqa: E402
from baselines.rl.train import train  # noqa: E402
from baselines.rl.wrappers import ObservationPipeline  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402

ENV = "bounce_gym/BounceNavigation-v0"
NAV = {"world": "square", "backend": "cell", "angles": [90, 135], "history": 2}


def _trained(tmp_path, **extra):
    config = {"name": "n", "env": ENV, "env_kwargs": NAV, "algo": "ppo", "n_envs": 2,
              "total_timesteps": 256, "models": str(tmp_path),
              "hyperparams": {"n_steps": 64, "batch_size": 64, "n_epochs": 1}, **extra}
    (path,) = train(config, progress=False)
    return path


def _sb3_pipeline(path, n_stack):
    """SB3's own evaluation pipeline: the statistics from the model file, frozen."""
    wrappers = read_model(path).metadata["wrappers"]
    venv = DummyVecEnv([lambda: gym.make(ENV, **NAV)])
    stats = wrappers["normalize"]
    venv = VecNormalize(venv, training=False, norm_obs=True, norm_reward=False,
                        clip_obs=stats["clip_obs"], epsilon=stats["epsilon"])
    venv.obs_rms.mean = np.array(stats["obs_rms"]["mean"])
    venv.obs_rms.var = np.array(stats["obs_rms"]["var"])
    return VecFrameStack(venv, n_stack)


def test_a_stacked_normalised_model_acts_as_in_sb3s_pipeline(tmp_path):
    path = _trained(tmp_path, n_stack=3, normalize=True)
    wrappers = read_model(path).metadata["wrappers"]
    assert wrappers["n_stack"] == 3 and wrappers["normalize"]["norm_obs"]
    assert wrappers["normalize"]["obs_rms"]["count"] > 256  # statistics of the training run
    env = gym.make(ENV, **NAV)
    policy = SB3Policy(path, env, deterministic=True)
    pipeline = _sb3_pipeline(path, 3)
    for seed in (0, 1):
        pipeline.seed(seed)
        stacked = pipeline.reset()
        obs, info = env.reset(seed=seed)
        policy.reset(env)
        for _ in range(40):
            expected, _ = policy.model.predict(stacked, deterministic=True)
            assert np.array_equal(pipeline.get_original_obs()[0], obs)  # the same observation
            action = policy.act(obs, info)
            assert action == int(expected[0])
            stacked, _, done, _ = pipeline.step(expected)
            obs, _, terminated, truncated, info = env.step(action)
            assert done[0] == (terminated or truncated)
            if done[0]:
                break


def test_without_its_wrappers_the_model_would_act_differently(tmp_path):
    """The check above can fail: the stack and the statistics change the actions."""
    path = _trained(tmp_path, n_stack=3, normalize=True)
    env = gym.make(ENV, **NAV)
    policy = SB3Policy(path, env)
    obs, info = env.reset(seed=0)
    policy.reset(env)
    raw = np.tile(obs, 3)[None]
    stacked = policy.pipeline.first(obs)
    assert stacked.shape == raw.shape and not np.allclose(stacked, raw)


@pytest.mark.parametrize(("wrappers", "message"), [
    ({"n_stack": 0}, r"wrappers.n_stack: expected an integer >= 1, got 0"),
    ({"normalize": {"norm_obs": True, "clip_obs": 10, "epsilon": 1e-8}},
     r"wrappers.normalize: incomplete or not numbers"),
    ({"normalize": {"norm_obs": True, "clip_obs": 10, "epsilon": 1e-8,
                    "obs_rms": {"mean": [0.0, 0.0], "var": [1.0, 1.0], "count": 1}}},
     r"wrappers.normalize.obs_rms: expected finite mean and var >= 0 of shape \(1,\)"),
])
def test_bad_wrappers_in_a_model_file_are_one_error(wrappers, message):
    env = gym.make("bounce_gym/Bounce-v0")
    with pytest.raises(ConfigError, match=f"model m.zip: {message}"):
        ObservationPipeline(wrappers, env.observation_space, env.action_space, Path("m.zip"))


def test_the_evaluation_scores_a_stacked_model_beside_a_plain_one(tmp_path):
    from bounce_gym_experiments.runner import run

    _trained(tmp_path, n_stack=2, normalize=True, variant="stack2")
    _trained(tmp_path)
    config = {"models": str(tmp_path), "experiments": [
        {"name": "n", "env": ENV, "env_kwargs": NAV, "seeds": [10_000, 10_001], "max_steps": 20,
         "horizon_reason": "a short check", "policies": ["rl"]}]}
    rows, _ = run(config, progress=False)
    assert sorted({r.policy for r in rows}) == [
        "rl ppo-stack2_seed0", "rl ppo-stack2_seed0 (greedy)", "rl ppo_seed0",
        "rl ppo_seed0 (greedy)"]
    # one row per variant, sampled and greedy
    assert sorted({r.group for r in rows}) == ["rl ppo", "rl ppo (greedy)", "rl ppo-stack2",
                                               "rl ppo-stack2 (greedy)"]
