"""The Drifter-v0 policies: the value-iteration policy acts π(info["state"]), its executed success
matches the model's predicted reach probability, and the baselines act legally."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from baselines.drifters import (
    AlwaysDriftPolicy,
    RandomLayerPolicy,
    ValueIterationPolicy,
    deploy_cells,
    deployment_locations,
    persistent_behavior,
)
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow


def test_value_iteration_policy_executes_its_predicted_success_on_the_cell_model():
    model = DrifterCells(get_flow("scb_like"), t=0.0)
    goal = model.state_of(0, [1, 2, 3], [25, 25, 25])
    policy = ValueIterationPolicy()
    res = policy.plan(model, goal)
    assert policy.plan(model, goal[::-1]) is res  # cached per model and goal
    start = int(model.state_of(0, 14, 8))
    horizon, n = 20, 2000
    rng = np.random.default_rng(1)
    state = np.full(n, start)
    done = np.zeros(n, dtype=bool)
    for _ in range(horizon):
        actions = np.array([policy.act(None, {"state": s}) for s in state])
        state = np.where(done, state, model.sample(state, actions, rng))
        done |= np.isin(state, goal)
    predicted = policy.predicted_success(start, horizon)
    assert 0.05 < predicted < 0.95
    assert done.mean() == pytest.approx(predicted, abs=4 * np.sqrt(0.25 / n))


def test_policies_refuse_what_they_cannot_act_on():
    with pytest.raises(ConfigError, match="reset"):
        ValueIterationPolicy().act(None, {"state": 0})
    policy = ValueIterationPolicy()
    policy.plan(DrifterCells(get_flow("two_sink")), 5)
    with pytest.raises(ConfigError, match="state"):
        policy.act(None, {})
    with pytest.raises(ConfigError, match="action_mask"):
        RandomLayerPolicy(0).act(None, {"state": 0})
    assert AlwaysDriftPolicy().act(None, {}) == DRIFT


def test_random_layer_policy_acts_legally_and_is_seeded():
    mask = np.array([True, False, True])
    a = RandomLayerPolicy(seed=3)
    a.start_options(None, 10_000)
    b = RandomLayerPolicy(seed=3)
    b.start_options(None, 10_001)  # its own seed wins over the episode's
    first = [a.act(None, {"action_mask": mask}) for _ in range(50)]
    assert first == [b.act(None, {"action_mask": mask}) for _ in range(50)]
    assert set(first) == {0, 2}


def test_deploy_cells_are_the_deployment_cells():
    model = DrifterCells(get_flow("two_sink"))
    dep = deployment_locations(persistent_behavior(model))
    cells = deploy_cells(model, dep.states)
    assert len(cells) == len(dep)
    assert [int(model.state_of(*c)) for c in cells] == dep.states.tolist()


needs_env = pytest.mark.skipif("bounce_gym/Drifter-v0" not in gym.registry,
                               reason="bounce_gym/Drifter-v0 is not registered on this branch")


@needs_env
def test_in_the_cell_env_success_equals_the_predicted_reach_probability():
    goal = {"cell": (0, 5, 5), "halo": 1}
    start = (0, 14, 8)
    env = gym.make("bounce_gym/Drifter-v0", flow="scb_like", backend="cell", task="reach",
                   goal=goal, start=start, max_episode_steps=15)
    policy = ValueIterationPolicy()
    n, successes, horizon = 1000, 0, None
    for episode in range(n):
        options = policy.start_options(env, episode)
        _, info = env.reset(seed=episode, options=options)
        policy.reset(env)
        steps = 0
        while True:
            _, _, terminated, truncated, info = env.step(policy.act(None, info))
            steps += 1
            if terminated or truncated:
                successes += bool(terminated)
                horizon = steps if truncated else horizon
                break
    env.close()
    model = env.unwrapped.cell_model()
    assert horizon is not None  # some episode ran into the time limit
    predicted = policy.predicted_success(int(model.state_of(*start)), horizon)
    assert 0.2 < predicted < 0.8
    assert successes / n == pytest.approx(predicted, abs=4 * np.sqrt(0.25 / n))
