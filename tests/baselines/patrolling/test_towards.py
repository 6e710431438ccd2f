"""The towards-vertex chains of Alg. 4.1 (Alam 2018, thesis §4.4.1) on the small graph of thesis
§4.5.2 and on small grids."""


import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.markov import hitting_times
from baselines.patrolling.towards import towards_vertex_chain, towards_vertex_chains
from bounce_gym.errors import ConfigError


@pytest.mark.parametrize("k", [1, 3, 6])
def test_every_vertex_leads_to_the_target(cvx_small_graph, k):
    chains = towards_vertex_chains(cvx_small_graph, k=k)
    nodes = sorted(cvx_small_graph)
    assert len(chains) == 8
    for i, M in enumerate(chains):
        assert M.shape == (8, 8) and M.min() >= 0
        np.testing.assert_allclose(M.sum(axis=1), 1.0, rtol=1e-12)
        assert np.isfinite(hitting_times(M, targets=[i])).all()
        # the target's row is uniform over its edges
        neighbours = [nodes.index(b) for b in cvx_small_graph[nodes[i]]]
        expected = np.zeros(8)
        expected[neighbours] = 1.0 / len(neighbours)
        np.testing.assert_allclose(M[i], expected)
        # moves only along edges
        for a, b in zip(*np.nonzero(M), strict=True):
            assert cvx_small_graph.has_edge(nodes[a], nodes[b])


def test_one_shortest_path_per_vertex_on_a_line():
    # k = 1 on a path graph: every vertex steps towards the target, so the walk from the target
    # returns in 2 steps and the far end is never visited again
    M = towards_vertex_chain(nx.path_graph(5), 2, k=1)
    np.testing.assert_allclose(M, [[0, 1, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0.5, 0, 0.5, 0],
                                   [0, 0, 1, 0, 0], [0, 0, 0, 1, 0]])
    H = hitting_times(M)
    assert H[0, 2] == 2 and H[4, 2] == 2
    assert np.isinf(H[2, 0]) and np.isinf(H[1, 4])  # reducible: the ends are never revisited


def test_counts_follow_the_k_shortest_paths():
    # a 4-cycle 0-1-2-3 with the chord 0-2; towards 2 with k = 2 the paths are
    # 0: 0-2 (1.5), 0-1-2 (2);  1: 1-2 (1), 1-0-2 (2.5);  3: 3-2 (1), 3-0-2 (2.7)
    graph = nx.cycle_graph(4)
    nx.set_edge_attributes(graph, 1.0, "length")
    graph.add_edge(0, 2, length=1.5)
    graph.edges[0, 3]["length"] = 1.2
    M = towards_vertex_chain(graph, 2, k=2)
    np.testing.assert_allclose(M, [[0, 1 / 4, 3 / 4, 0], [1 / 3, 0, 2 / 3, 0],
                                   [1 / 3, 1 / 3, 0, 1 / 3], [1 / 2, 0, 1 / 2, 0]])


def test_node_order_is_sorted():
    graph = nx.Graph([(3, 1), (1, 2), (2, 0)])
    M = towards_vertex_chain(graph, 0, k=1)
    np.testing.assert_allclose(M, [[0, 0, 1, 0], [0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0]])


def test_more_paths_spread_the_chain_on_a_grid():
    grid = nx.convert_node_labels_to_integers(nx.grid_2d_graph(4, 4))
    one, three = towards_vertex_chain(grid, 5, k=1), towards_vertex_chain(grid, 5, k=3)
    assert np.count_nonzero(three) > np.count_nonzero(one)
    for M in (one, three):
        assert np.isfinite(hitting_times(M, targets=[5])).all()


def test_bad_inputs_are_named(cvx_small_graph):
    for k in (0, -1, 1.5, True):
        with pytest.raises(ConfigError, match="k"):
            towards_vertex_chain(cvx_small_graph, 1, k=k)
    with pytest.raises(ConfigError, match="target"):
        towards_vertex_chain(cvx_small_graph, 9)
    with pytest.raises(ConfigError, match="graph"):
        towards_vertex_chains(nx.Graph([(0, 1), (2, 3)]))
