"""Trained agents play sampled actions by default (`baselines.rl.policies.SB3Policy`,
`baselines.rl.action_draws`): drawn from the model's distribution with a generator restarted
from the episode's seed, so an episode repeats given its seed (whatever ran before, whatever
torch's global random state, in this process or a pool's), and differs from the greedy one."""

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

pytest.importorskip("stable_baselines3")
pytest.importorskip("sb3_contrib")

import torch  # noqa: E402

import bounce_gym  # noqa: E402,F401
from baselines.rl.policies import SB3Policy  # noqa: E402
from baselines.rl.train import train  # noqa: E402

ENV = "bounce_gym/BounceNavigation-v0"
NAV = {"world": "square", "backend": "cell", "angles": [45, 90, 135]}
CONTINUOUS = {"world": "square", "backend": "kinematic", "action_type": "continuous"}
#: per model: its folder, env options and training hyperparameters (DQN explores often, so
#: that its ε-greedy draws show in a short episode)
MODELS = {
    "ppo": ("ppo", NAV, {"n_steps": 64, "batch_size": 64, "n_epochs": 1}),
    "ppo-continuous": ("ppo", CONTINUOUS, {"n_steps": 64, "batch_size": 64, "n_epochs": 1}),
    "ppo-sde": ("ppo", CONTINUOUS, {"n_steps": 64, "batch_size": 64, "n_epochs": 1,
                                    "use_sde": True}),
    "recurrentppo": ("recurrentppo", NAV, {"n_steps": 64, "batch_size": 64, "n_epochs": 1}),
    "dqn": ("dqn", NAV, {"learning_starts": 32, "buffer_size": 256, "batch_size": 32,
                         "exploration_final_eps": 0.3}),
}
#: episode seeds the first action is drawn with, to compare its frequencies with the model's
DRAWS = range(10_000, 10_400)


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    folder = tmp_path_factory.mktemp("models")
    out = {}
    for name, (algo, env_kwargs, hyperparams) in MODELS.items():
        (path,) = train({"name": name, "env": ENV, "env_kwargs": env_kwargs, "algo": algo,
                         "n_envs": 1, "total_timesteps": 128, "hyperparams": hyperparams,
                         "models": str(folder)}, progress=False)
        out[name] = path
    return out


def _env(name):
    return gym.make(ENV, max_episode_steps=40, **MODELS[name][1])


def _episode(policy, env, seed):
    """The actions of one episode, in the runner's call order (`baselines.policy`)."""
    policy.start_options(env, seed)
    obs, info = env.reset(seed=seed)
    policy.reset(env)
    actions, done = [], False
    while not done:
        action = policy.act(obs, info)
        actions.append(np.asarray(action, dtype=float).ravel().tolist())
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
    return actions


@pytest.mark.parametrize("name", list(MODELS))
def test_sampled_episodes_repeat_with_their_seed_and_differ_from_greedy(models, name):
    env = _env(name)
    sampled = SB3Policy(models[name], env)
    first = _episode(sampled, env, 10_000)
    _episode(sampled, env, 10_001)
    torch.manual_seed(12_345)  # torch's global stream plays no part
    assert _episode(sampled, env, 10_000) == first
    assert _episode(SB3Policy(models[name], env), env, 10_000) == first  # a fresh load
    greedy = SB3Policy(models[name], env, deterministic=True)
    assert greedy.name.endswith(" (greedy)") and not sampled.name.endswith(" (greedy)")
    assert _episode(greedy, env, 10_000) != first
    env.close()


def _first_actions(policy, env):
    """The first action of every seed of `DRAWS`, all from the same observation."""
    obs, info = env.reset(seed=0)
    out = []
    for seed in DRAWS:
        policy.start_options(env, seed)
        policy.reset(env)
        out.append(policy.act(obs, info))
    return obs, np.array(out, dtype=float).reshape(len(DRAWS), -1)


def _distribution(policy, obs):
    batch, _ = policy.model.policy.obs_to_tensor(obs[None])
    with torch.no_grad():
        if hasattr(policy.model.policy, "lstm_hidden_state_shape"):
            zeros = torch.zeros(policy.model.policy.lstm_hidden_state_shape)
            dist, _ = policy.model.policy.get_distribution(batch, (zeros, zeros),
                                                           torch.ones(1))
        else:
            dist = policy.model.policy.get_distribution(batch)
    return dist.distribution


@pytest.mark.parametrize("name", ["ppo", "recurrentppo"])
def test_categorical_draws_follow_the_models_probabilities(models, name):
    env = _env(name)
    policy = SB3Policy(models[name], env)
    obs, drawn = _first_actions(policy, env)
    probs = _distribution(policy, obs).probs.numpy()[0].astype(float)
    counts = np.bincount(drawn[:, 0].astype(int), minlength=len(probs))
    assert stats.chisquare(counts, probs / probs.sum() * len(DRAWS)).pvalue > 1e-4
    assert (counts > 0).sum() >= 2  # not one action every time, as the greedy policy plays
    env.close()


@pytest.mark.parametrize("name", ["ppo-continuous", "ppo-sde"])
def test_gaussian_draws_follow_the_models_distribution_clipped_to_the_bounds(models, name):
    env = _env(name)
    policy = SB3Policy(models[name], env)
    obs, drawn = _first_actions(policy, env)
    normal = _distribution(policy, obs)
    mean, std = float(normal.mean[0, 0]), float(normal.stddev[0, 0])
    x = drawn[:, 0]
    assert ((x >= -1.0) & (x <= 1.0)).all()
    # clipped at the bounds as often as the normal falls beyond them
    below, above = stats.norm.cdf(-1.0, mean, std), stats.norm.sf(1.0, mean, std)
    counts = [(x == -1.0).sum(), ((x > -1.0) & (x < 1.0)).sum(), (x == 1.0).sum()]
    expected = np.array([below, 1.0 - below - above, above]) * len(x)
    assert stats.chisquare(counts, expected).pvalue > 1e-4
    # and between them the normal itself
    inside = x[(x > -1.0) & (x < 1.0)]
    truncated = stats.truncnorm((-1.0 - mean) / std, (1.0 - mean) / std, mean, std)
    assert stats.kstest(inside, truncated.cdf).pvalue > 1e-4
    env.close()


def test_dqn_explores_at_its_final_rate(models):
    env = _env("dqn")
    policy = SB3Policy(models["dqn"], env)
    assert policy.model.exploration_final_eps == 0.3
    obs, drawn = _first_actions(policy, env)
    greedy = SB3Policy(models["dqn"], env, deterministic=True)
    greedy.reset(env)
    best = greedy.act(obs, {})
    # a random action differs from the greedy one with probability ε (n - 1) / n
    other = int((drawn[:, 0] != best).sum())
    n = env.action_space.n
    assert stats.binomtest(other, len(DRAWS), 0.3 * (n - 1) / n).pvalue > 1e-4
    env.close()


def test_the_recurrent_state_is_carried_as_sb3_carries_it(models):
    """The LSTM state after each sampled step is the one SB3's own predict reaches on the
    same observations."""
    env = _env("recurrentppo")
    policy = SB3Policy(models["recurrentppo"], env)
    policy.start_options(env, 10_000)
    obs, info = env.reset(seed=10_000)
    policy.reset(env)
    state, start, done, steps = None, np.ones(1, dtype=bool), False, 0
    while not done:
        _, state = policy.model.predict(obs[None], state=state, episode_start=start)
        start = np.zeros(1, dtype=bool)
        action = policy.act(obs, info)
        assert all(np.allclose(a, b, atol=1e-6) for a, b in zip(policy.state, state,
                                                                  strict=True))
        obs, _, terminated, truncated, info = env.step(action)
        done, steps = terminated or truncated, steps + 1
    assert steps >= 2
    env.close()


def test_a_pool_of_two_plays_the_same_sampled_episodes_as_one_process(models):
    from bounce_gym_experiments.executors import make_executor
    from bounce_gym_experiments.runner import run

    config = {"models": str(models["ppo"].parents[1]), "experiments": [
        {"name": "n", "env": ENV, "env_kwargs": NAV, "seeds": list(range(10_000, 10_012)),
         "max_steps": 40, "horizon_reason": "a short check", "policies": ["rl"],
         "rl_models": "ppo"}]}
    here, _ = run(config, progress=False)
    pooled, _ = run(config, progress=False, executor=make_executor(workers=2))
    assert [r.row() for r in pooled] == [r.row() for r in here]
    assert {r.policy for r in here} == {"rl ppo_seed0", "rl ppo_seed0 (greedy)"}


def test_a_model_with_squashed_actions_is_refused_for_sampling():
    from stable_baselines3 import PPO

    from baselines.rl.action_draws import check_drawable
    from bounce_gym.errors import ConfigError

    env = gym.make(ENV, **CONTINUOUS)
    model = PPO("MlpPolicy", env, use_sde=True, policy_kwargs={"squash_output": True},
                device="cpu")
    with pytest.raises(ConfigError, match=r"model m.zip: its actions follow a "
                                          r"StateDependentNoiseDistribution squashed"):
        check_drawable(model, "m.zip")
    check_drawable(PPO("MlpPolicy", env, device="cpu"), "m.zip")  # a plain Gaussian: drawn
    env.close()
