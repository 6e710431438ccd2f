"""The reference policies of Patrol-v0 (baselines.patrolling.policies): Markov-chain patrollers,
perimeter patrols, the Stackelberg best response and the joint policy."""

import networkx as nx
import numpy as np
import pytest
from scipy import stats as scipy_stats

from baselines.patrolling import cell_graph, solve_maect
from baselines.patrolling.policies import (
    BestResponseAdversary,
    JointPatrolPolicy,
    MarkovPatrolPolicy,
    PerimeterPatrolPolicy,
    induced_chain,
    perimeter_walk,
)
from bounce_gym.envs.patrol.env import PatrolEnv
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import zoo


@pytest.fixture(scope="module")
def env():
    made = PatrolEnv(world="grid_10x10", sensor_range=2.0, attack_time=5, n_patrollers=2)
    yield made
    made.close()


def play(env, policy, seed, steps=30):
    """Vertices of every patroller after each step, and the infos' illegal flags."""
    options = policy.start_options(env, seed)
    obs, infos = env.reset(seed=seed, options=options)
    policy.reset(env)
    path, illegal = [env.positions()], []
    for _ in range(steps):
        if not env.agents:
            break
        obs, _, _, _, infos = env.step(policy.act(obs, infos))
        path.append(env.positions())
        illegal += [info["illegal_action"] for info in infos.values()]
    return np.array(path), illegal


class Waiting(BestResponseAdversary):
    """An adversary that never attacks, so that an episode runs until it is deterred."""

    def act(self, observations, infos):
        return dict.fromkeys(observations, 0)


@pytest.mark.parametrize("world", ["grid_10x10", "patrol_15x15"])
def test_the_perimeter_walk_visits_every_vertex_along_edges(world):
    graph = cell_graph(zoo.get(world))
    walk = perimeter_walk(graph)
    assert set(walk) == set(graph)
    assert all(graph.has_edge(a, b) for a, b in zip(walk, walk[1:] + walk[:1], strict=True))


def test_the_induced_chain_moves_to_the_walks_neighbours_half_and_half():
    cycle = nx.cycle_graph(6)
    nx.set_edge_attributes(cycle, 1.0, "length")
    walk = perimeter_walk(cycle)
    P = induced_chain(walk, 6)
    expected = np.zeros((6, 6))
    for v in range(6):
        expected[v, (v + 1) % 6] = expected[v, (v - 1) % 6] = 0.5
    assert np.allclose(P, expected)
    with pytest.raises(ConfigError, match="walk: vertex 5 is not on it"):
        induced_chain([0, 1, 2, 3, 4], 6)


def test_markov_patrollers_are_reproducible_per_seed_and_move_only_along_edges(env):
    policy = JointPatrolPolicy(MarkovPatrolPolicy([env.strategy], name="walk"), Waiting())
    first, illegal = play(env, policy, 10_000)
    again, _ = play(env, policy, 10_000)
    other, _ = play(env, policy, 10_001)
    assert len(first) == 31 and not any(illegal)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, other)
    for a, b in zip(first, first[1:], strict=False):
        assert all(env.graph.has_edge(u, v) for u, v in zip(a, b, strict=True))


def test_one_chain_per_episode_is_drawn_with_the_mixtures_weights(env):
    maect = solve_maect(env.graph).transition
    policy = MarkovPatrolPolicy([env.strategy, maect], [0.25, 0.75])
    drawn = []
    for seed in range(10_000, 10_400):
        policy.start_options(env, seed)
        policy.reset(env)
        drawn.append(policy.chain)
    assert scipy_stats.binomtest(sum(drawn), 400, 0.75).pvalue > 0.001
    assert [(w, c.shape) for w, c in policy.told(env)] == [(0.25, (87, 87)), (0.75, (87, 87))]


def test_the_best_response_attacks_the_least_guarded_target_lowest_index_first(env):
    env.reset(seed=10_000)
    for mode, predicted in (("strategy", env.capture_probabilities()),
                            ("positions", env.capture_probabilities(env.positions()))):
        adversary = BestResponseAdversary(mode)
        adversary.reset(env)
        assert np.allclose(adversary.capture_probabilities(env), predicted, atol=1e-12)
        least = np.flatnonzero(np.isclose(predicted, predicted.min(), rtol=0, atol=1e-12))
        assert adversary.target == least[0]
        assert adversary.predicted == pytest.approx(predicted.min())
        assert adversary.act({"adversary": None}, {}) == {"adversary": 1 + adversary.target}
        assert adversary.act({"adversary": None}, {}) == {"adversary": 0}


def test_against_a_mixture_the_best_response_mixes_the_capture_probabilities(env):
    maect = solve_maect(env.graph).transition.toarray()
    joint = JointPatrolPolicy(MarkovPatrolPolicy([env.strategy, maect], [0.5, 0.5]),
                              BestResponseAdversary())
    options = joint.start_options(env, 10_000)
    assert np.allclose(options["strategy"], 0.5 * (env.strategy + maect))
    env.reset(seed=10_000, options={"strategy": maect})
    with_maect = env.capture_probabilities()
    env.reset(seed=10_000)
    with_walk = env.capture_probabilities()
    assert np.allclose(joint.adversary.capture_probabilities(env),
                       0.5 * (with_maect + with_walk))


@pytest.mark.parametrize("p", ["deterministic", "random_walk"])
def test_perimeter_patrollers_start_equally_spaced_and_follow_the_walk(env, p):
    policy = PerimeterPatrolPolicy(p)
    joint = JointPatrolPolicy(policy, Waiting())
    walk = policy.walk(env)
    path, illegal = play(env, joint, 10_000, steps=40)
    assert not any(illegal)
    assert (policy.index[1] - policy.index[0]) % len(walk) in (len(walk) // 2,
                                                               (len(walk) + 1) // 2)
    for a, b in zip(path, path[1:], strict=False):
        assert all(env.graph.has_edge(u, v) for u, v in zip(a, b, strict=True))
    if p == "deterministic":  # a sweep: 40 steps along the walk in one direction
        start = policy.index[0] - 40 * policy.direction
        expected = [walk[(start + policy.direction * k) % len(walk)] for k in range(41)]
        assert path[:, 0].tolist() == expected


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: MarkovPatrolPolicy([]), "chains: expected at least one"),
        (lambda: MarkovPatrolPolicy([np.full((3, 3), 0.5)]), r"chains\[0\]: rows must"),
        (lambda: MarkovPatrolPolicy([np.eye(3), np.eye(4)]), r"chains\[1\]: expected 3 x 3"),
        (lambda: MarkovPatrolPolicy([np.eye(3)], [1.0, 0.0]), "weights: expected 1"),
        (lambda: BestResponseAdversary("omniscient"), "mode: expected one of"),
        (lambda: PerimeterPatrolPolicy("sometimes"), "p: expected a number in"),
        (lambda: PerimeterPatrolPolicy(1.5), "p: expected a number in"),
        (lambda: perimeter_walk(nx.empty_graph(3)), "graph: a perimeter walk needs"),
    ],
)
def test_bad_arguments_raise_naming_them(make, message):
    with pytest.raises(ConfigError, match=message):
        make()
