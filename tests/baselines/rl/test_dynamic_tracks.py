"""The two RL tracks on pymunk's dynamic physics with rotation noise (docs/learning.md, "RL on
dynamic physics"): the "contact and clock" learners see only contact, clock, the sensed history
and the task's givens, and their policies act without reading ``info``; the "pose observed"
learner is the privileged one and is named so."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from baselines.rl.train_config import validate_train_config
from baselines.rl.train_env import make_config_env
from bounce_gym.documents import read_document

ROOT = Path(__file__).parents[3]
CONFIGS = ROOT / "configs"
AGENTS = ROOT / "baselines" / "agents"
#: the contact-and-clock track's training configurations, by the benchmark row they feed
CONTACT_AND_CLOCK = {"navigation-lab-dynamic-noise": "train_navigation_dynamic_recurrent.yaml",
                     "localization-lab-dynamic-noise": "train_localization_dynamic_recurrent.yaml"}
POSE_OBSERVED = {"navigation-lab-v1-dynamic-noise": "train_navigation_v1_dynamic_her.yaml"}
#: observation features a navigation v0 task adds: the start and goal poses (4 numbers each)
TASK_FEATURES = 8


def _config(file: str) -> dict:
    return validate_train_config(read_document(CONFIGS / file), CONFIGS)


def _env(file: str):
    return make_config_env(_config(file))


@pytest.mark.parametrize("file", [*CONTACT_AND_CLOCK.values(), *POSE_OBSERVED.values()])
def test_the_tracks_train_on_dynamic_physics_with_noise(file):
    config = _config(file)
    kwargs = config["env_kwargs"]
    assert (kwargs["backend"], kwargs["physics"]) == ("pymunk", "dynamic")
    assert kwargs["noise"] == {"type": "reliable", "r": 0.9, "eps_deg": 5}
    assert config["vec_env"] == "sync"  # the default: the batched env refuses dynamic physics
    assert len(config["seeds"]) >= 5


def test_only_the_pose_observed_track_observes_the_pose():
    for name, file in {**CONTACT_AND_CLOCK, **POSE_OBSERVED}.items():
        assert _config(file)["name"] == name
        assert _env(file).unwrapped.observes_pose == (name in POSE_OBSERVED), name


@pytest.mark.parametrize("file", CONTACT_AND_CLOCK.values())
def test_the_observation_holds_clock_history_and_givens_only(file):
    config = _config(file)
    env = make_config_env(config)
    options = env.unwrapped.options
    givens = TASK_FEATURES if config["env"].endswith("Navigation-v0") else 0
    assert not options.privileged and options.step_mode == "bounce"
    # bounce steps of a lone robot: every step ends in contact, so the clock is the sensor
    assert env.observation_space.shape == (1 + 2 * options.history + givens,)


@pytest.mark.parametrize("file", CONTACT_AND_CLOCK.values())
def test_the_observation_does_not_change_with_the_pose(file):
    """Each observation of a few steps is what the robot senses: moving the true robot elsewhere
    (its clock and history kept) leaves it unchanged, and the task's givens stay those of the
    episode's start."""
    env = _env(file)
    core = env.unwrapped.core
    obs, _ = env.reset(seed=10000)
    givens = obs[1 + 2 * env.unwrapped.options.history:]
    for step in range(4):
        state = core.dynamics.state
        pose = state.position.copy(), state.heading.copy()
        state.position += (0.31, -0.17)
        state.heading += 1.0 + step
        assert np.array_equal(core.observation()[0], obs)
        state.position[:], state.heading[:] = pose
        obs, _, terminated, truncated, _ = env.step(step % env.action_space.n)
        assert np.array_equal(obs[len(obs) - len(givens):], givens)
        if terminated or truncated:
            break


def test_a_dynamic_env_survives_pickling():
    """SubprocVecEnv sends env factories, and resuming restores pickled envs: a copy of a dynamic
    env goes on exactly as the original."""
    env = _env(CONTACT_AND_CLOCK["navigation-lab-dynamic-noise"])
    env.reset(seed=10001)
    copy = pickle.loads(pickle.dumps(env))  # noqa: S301  (our own bytes)
    for action in (0, 2, 1):
        assert np.array_equal(env.step(action)[0], copy.step(action)[0])


class _Untouchable:
    """An ``info`` that fails the test when a policy reads anything from it."""

    def __getattr__(self, name):
        raise AssertionError(f"the policy read info.{name}")

    def __getitem__(self, key):
        raise AssertionError(f"the policy read info[{key!r}]")

    def __contains__(self, key):
        raise AssertionError(f"the policy asked whether info has {key!r}")

    def __iter__(self):
        raise AssertionError("the policy iterated over info")


@pytest.mark.parametrize("name", CONTACT_AND_CLOCK)
def test_a_shipped_contact_and_clock_agent_acts_without_info(name):
    from baselines.rl.policies import SB3Policy

    models = sorted((AGENTS / name).glob("*_seed*.zip"))
    assert len(models) >= 5
    env = _env(CONTACT_AND_CLOCK[name])
    policy = SB3Policy(models[0], env)
    obs, _ = env.reset(seed=10002)
    policy.start_options(env, 10002)
    policy.reset(env)
    for _ in range(3):
        action = policy.act(obs, _Untouchable())
        assert env.action_space.contains(action)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
