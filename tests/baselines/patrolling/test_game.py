"""The patrolling game (Alam 2018, thesis §4.4.2 and §4.5.2): Alg. 4.2 payoffs against Table 4.2
and the strong Stackelberg equilibrium against Table 4.3."""

import itertools

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.game import (
    payoff_matrices,
    preferred_all,
    preferred_subset,
    preferred_towards,
    stackelberg,
)
from baselines.patrolling.maect import solve_maect
from baselines.patrolling.markov import hitting_times, transition_matrix
from bounce_gym.errors import ConfigError


def test_every_table_4_2_entry_follows_from_the_vertex_ranking(table_4_2):
    P_TABLE, Q_TABLE = table_4_2
    # each printed row ranks the vertices by its P entries (8 = rank 1, 3.5625 = rank 2, ...)
    P, Q = payoff_matrices(-P_TABLE)
    np.testing.assert_allclose(P, P_TABLE, atol=5e-5)
    np.testing.assert_allclose(Q, Q_TABLE, atol=5e-5)
    assert P.shape == (10, 8)


def test_maect_row_of_table_4_2_from_the_optimal_chain(cvx_small_graph, table_4_2):
    P_TABLE, Q_TABLE = table_4_2
    graph = nx.Graph(list(cvx_small_graph.edges()))
    result = solve_maect(graph)
    H = hitting_times(result.transition)
    order = [result.nodes.index(v) for v in range(1, 9)]
    preferred = preferred_all(H[np.ix_(order, order)])
    P, Q = payoff_matrices(preferred[None, :])
    # v3 and v8 are swapped by a symmetry of the graph: their tie goes to v3 (the lower index)
    np.testing.assert_allclose(P[0], P_TABLE[8], atol=5e-5)
    np.testing.assert_allclose(Q[0], Q_TABLE[8], atol=5e-5)


def test_payoff_values_are_the_ranked_sets_and_inf_ranks_last():
    P, Q = payoff_matrices(np.array([[np.inf, 2.0, 1.0, 2.0]]))
    n = 4
    r = np.array([4, 2, 1, 3])  # ties (2.0, 2.0) keep index order; inf last
    p = 0.5 ** (r - 1)
    np.testing.assert_allclose(P[0], p * (n + 1 - r) + (1 - p) / n)
    np.testing.assert_allclose(Q[0], p * r + (1 - p) / n)


def test_preferred_hitting_times():
    P, _ = transition_matrix(nx.path_graph(4))
    H = hitting_times(P)
    np.testing.assert_allclose(preferred_all(H), H.mean(axis=0))
    np.testing.assert_allclose(preferred_subset(H, [0, 3]), (H[:, 0] + H[:, 3]) / 2)
    np.testing.assert_allclose(preferred_towards(H, 2), H[:, 2])
    with pytest.raises(ConfigError, match="subset"):
        preferred_subset(H, [])


def test_table_4_3_equilibrium(table_4_2):
    P_TABLE, Q_TABLE = table_4_2
    result = stackelberg(P_TABLE, Q_TABLE)
    assert result.value == pytest.approx(8.0, abs=1e-6)
    assert result.attack == 6  # v7
    expected = np.zeros(10)
    expected[6], expected[8] = 73 / 81, 8 / 81  # strategies 7 and 9 (MAECT)
    np.testing.assert_allclose(result.mixture, expected, atol=1e-4)
    assert result.mixture.sum() == pytest.approx(1.0)


def brute_force(P: np.ndarray, Q: np.ndarray, steps: int) -> float:
    """Best leader value over a grid of the 3-simplex; the follower best-responds and breaks
    ties for the leader."""
    grid = np.array([(a, b, steps - a - b) for a, b in itertools.product(range(steps + 1),
                                                                          repeat=2)
                     if a + b <= steps], dtype=float) / steps
    leader, follower = grid @ P, grid @ Q
    best_response = follower >= follower.max(axis=1, keepdims=True) - 1e-12
    return float(np.where(best_response, leader, -np.inf).max(axis=1).max())


@pytest.mark.parametrize("seed", range(8))
def test_random_3x3_games_match_a_brute_force_grid(seed):
    rng = np.random.default_rng(seed)
    P, Q = rng.uniform(0, 1, (3, 3)), rng.uniform(0, 1, (3, 3))
    result = stackelberg(P, Q)
    grid_value = brute_force(P, Q, 300)
    assert result.value >= grid_value - 1e-7  # the grid points are feasible mixtures
    assert result.value <= grid_value + 0.005
    # the reported attack is a best response to the mixture
    follower = result.mixture @ Q
    assert follower[result.attack] >= follower.max() - 1e-7


def test_bad_payoffs_are_named():
    with pytest.raises(ConfigError, match="P, Q"):
        stackelberg(np.ones((2, 3)), np.ones((3, 2)))
    with pytest.raises(ConfigError, match="preferred"):
        payoff_matrices(np.array([1.0, 2.0]))
