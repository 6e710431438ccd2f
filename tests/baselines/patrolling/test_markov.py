"""Random walks, hitting and commute times on patrol graphs (Alam 2018, thesis §4.4)."""

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.markov import (
    commute_times,
    hitting_times,
    mean_commute_time,
    transition_matrix,
)
from bounce_gym.errors import ConfigError


@pytest.mark.parametrize("n", [3, 8, 12])
def test_complete_graph_walk_hits_in_n_minus_1(n):
    P, nodes = transition_matrix(nx.complete_graph(n))
    H = hitting_times(P)
    off = ~np.eye(n, dtype=bool)
    np.testing.assert_allclose(H[off], n - 1, rtol=1e-12)
    assert np.all(np.diag(H) == 0) and nodes == list(range(n))


def test_weighted_walk_rows_follow_the_weights():
    graph = nx.path_graph(3)
    P, _ = transition_matrix(graph, {(0, 1): 0.25, (2, 1): 0.75})  # either orientation
    np.testing.assert_allclose(P.toarray(), [[0, 1, 0], [0.25, 0, 0.75], [0, 1, 0]])


def test_path_hitting_times_match_the_gamblers_ruin():
    # simple walk on a path 0..4: H[0, k] = k^2
    P, _ = transition_matrix(nx.path_graph(5))
    np.testing.assert_allclose(hitting_times(P, targets=[4])[:, 0], [16, 15, 12, 7, 0])
    np.testing.assert_allclose(hitting_times(P)[0], [0, 1, 4, 9, 16])


def test_reducible_chain_returns_inf_without_raising():
    P = np.array([[0, 0.5, 0.5, 0], [0, 0, 0, 1], [0, 0, 1, 0], [0, 1, 0, 0]])
    H = hitting_times(P)
    assert H[1, 3] == 1 and H[3, 1] == 1
    assert np.isinf(H[0, 1])  # half of the walks fall into the absorbing state 2
    assert np.isinf(H[2, 0]) and np.isinf(H[1, 0])
    assert H[0, 2] == np.inf  # half never reach 2 either
    assert np.isinf(mean_commute_time(P))


def test_commute_times_are_symmetric_sums():
    P, _ = transition_matrix(nx.cycle_graph(6))
    C = commute_times(P)
    H = hitting_times(P)
    np.testing.assert_allclose(C, H + H.T)
    np.testing.assert_allclose(C, C.T)


def test_bad_inputs_are_named():
    with pytest.raises(ConfigError, match="weights"):
        transition_matrix(nx.path_graph(3), {(0, 1): 1.0})
    with pytest.raises(ConfigError, match="weights"):
        transition_matrix(nx.path_graph(3), {(0, 1): 1.0, (1, 2): -1.0})
    with pytest.raises(ConfigError, match="weights"):
        transition_matrix(nx.path_graph(3), {(0, 1): 1.0, (1, 2): 0.0})
    with pytest.raises(ConfigError, match="P"):
        hitting_times(np.array([[0.5, 0.2], [0.0, 1.0]]))
