"""The fleet deployments in MultiDrifter-v0 (`DeploymentPolicy`), the expected coverage of a
deployment and the eventual visit probabilities."""

from __future__ import annotations

import numpy as np
import pettingzoo
import pytest

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.drifters import (
    DeploymentPolicy,
    deployment_locations,
    expected_coverage,
    greedy_deployment,
    persistent_behavior,
    visit_probabilities,
)
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow


@pytest.fixture(scope="module")
def behavior():
    return persistent_behavior(DrifterCells(get_flow("two_sink")), 0)


def fleet(n: int):
    return pettingzoo.make("parallel", "bounce_gym/MultiDrifter-v0", flow="two_sink",
                           n_drifters=n, max_cycles=5)


def test_expected_coverage_is_the_visit_formula(behavior):
    states = behavior.offset + np.array([3, 3, 40])  # a repeated cell counts as two drifters
    assert expected_coverage(behavior, states, visit_probabilities(behavior, 0)) == \
        pytest.approx(2 / behavior.n_cells)
    P = behavior.graph.toarray()
    one = P[[3, 3, 40]].copy()  # within one step: the release cell, or the cell stepped to
    one[[0, 1], 3] = 1.0
    one[2, 40] = 1.0
    expected = np.mean(1 - np.prod(1 - one, axis=0))
    assert expected_coverage(behavior, states, visit_probabilities(behavior, 1)) == \
        pytest.approx(expected)
    with pytest.raises(ConfigError, match="hit"):
        expected_coverage(behavior, states, np.eye(3))


def test_eventual_visits(behavior):
    """A transient cell is visited, if ever, before absorption (a few steps here), so long
    horizons reach its eventual probability; a persistent group is visited in full once
    entered, so its cells' eventual probability is the absorption probability of the group,
    however slowly the horizons approach it."""
    ever = visit_probabilities(behavior, None)
    long = visit_probabilities(behavior, 2000)
    assert np.all(long <= ever + 1e-9)
    transient = behavior.group_of < 0
    assert np.allclose(long[:, transient], ever[:, transient], atol=1e-9)
    persistent = ~transient
    assert np.allclose(ever[:, persistent],
                       behavior.absorption[:, behavior.group_of[persistent]], atol=1e-5)
    assert np.allclose(np.diag(ever), 1.0)


def test_the_fleet_is_released_at_the_deployment_and_drifts(behavior):
    env = fleet(5)
    policy = DeploymentPolicy("alg5.2")
    options = policy.start_options(env, 10_000)
    assert policy.deployment.states.tolist() == \
        deployment_locations(behavior, seed=10_000).states.tolist()
    observations, infos = env.reset(seed=10_000, options=options)
    assert sorted(int(i["state"]) for i in infos.values()) == \
        sorted(policy.deployment.states.tolist())
    assert policy.act(observations, infos) == dict.fromkeys(env.agents, DRIFT)
    env.close()


def test_random_and_greedy_deployments_release_as_many_drifters_as_the_env_has(behavior):
    env = fleet(7)
    random = DeploymentPolicy("random")
    first = random.start_options(env, 10_000)["deploy"]
    assert len(first) == 7 and len(set(first)) == 7
    assert random.start_options(env, 10_000)["deploy"] == first  # the episode's seed
    assert random.start_options(env, 10_001)["deploy"] != first
    greedy = DeploymentPolicy("greedy", horizon=50)
    assert greedy.name == "greedy deployment (H=50)"
    greedy.start_options(env, 10_000)
    assert greedy.deployment.states.tolist() == \
        greedy_deployment(behavior, 7, 50).states.tolist()
    with pytest.raises(ConfigError, match=r"n_drifters: Alg\. 5\.2 deploys 5 drifters"):
        DeploymentPolicy("alg5.2").start_options(env, 10_000)
    env.close()


@pytest.mark.parametrize(("method", "horizon", "message"), [
    ("best", None, "method: expected one of"),
    ("greedy", None, "horizon"),
    ("random", 10, "horizon"),
    ("greedy", 0, "horizon"),
])
def test_bad_deployment_policies_raise(method, horizon, message):
    with pytest.raises(ConfigError, match=message):
        DeploymentPolicy(method, horizon)
