"""MAECT (Alam 2018, thesis eq. 4.2-4.4): the Laplacian, the printed objective, its optima on the
graphs of thesis Fig. 4.5 and the CVX small graph of thesis §4.5.2, and the commute identity."""

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.maect import (
    incidence,
    laplacian,
    maect_objective,
    project_simplex,
    solve_maect,
)
from baselines.patrolling.markov import mean_commute_time, transition_matrix
from bounce_gym.errors import ConfigError

# the small graph of thesis §4.5.2 (8 vertices, 13 edges), 1-based, in its printed edge order
SMALL_EDGES = [(1, 2), (2, 3), (3, 4), (1, 5), (2, 8), (2, 4), (5, 6), (5, 7), (3, 7), (4, 8),
               (6, 7), (7, 8), (2, 7)]
SMALL_OPTIMUM = [0.11566, 0.05215, 0.06918, 0.10324, 0.05215, 0.06811, 0.08096, 0.06805, 0.09354,
                 0.06918, 0.10760, 0.09354, 0.02665]


def small_graph() -> nx.Graph:
    graph = nx.Graph()
    graph.add_nodes_from(range(1, 9))
    graph.add_edges_from(SMALL_EDGES)
    return graph


def tree_optimum(tree: nx.Graph) -> tuple[dict, float]:
    """Closed form on a tree: w_e ∝ sqrt(n_e (n - n_e)), objective 2/(n(n-1)) (Σ sqrt(...))²."""
    n = tree.number_of_nodes()
    raw = {}
    for u, v in tree.edges():
        cut = tree.copy()
        cut.remove_edge(u, v)
        side = len(nx.node_connected_component(cut, u))
        raw[(u, v)] = np.sqrt(side * (n - side))
    total = sum(raw.values())
    return {e: x / total for e, x in raw.items()}, 2.0 / (n * (n - 1)) * total**2


def test_laplacian_is_a_diag_w_a_transposed_and_psd():
    graph = small_graph()
    A = incidence(graph)
    w = np.random.default_rng(3).uniform(0.1, 1.0, graph.number_of_edges())
    L = laplacian(A, w)
    dense = A.toarray()
    np.testing.assert_allclose(L, dense @ np.diag(w) @ dense.T)
    lam, vec = np.linalg.eigh(L)
    assert lam[0] == pytest.approx(0.0, abs=1e-12) and np.all(lam[1:] > 0)
    np.testing.assert_allclose(np.abs(vec[:, 0]), 1 / np.sqrt(8), rtol=1e-9)
    # oriented as printed: +1 where the edge enters (its second vertex), -1 where it leaves
    assert dense[0, 0] == -1 and dense[1, 0] == 1


def test_complete_graph_k8_optimum_is_uniform_with_objective_7():
    result = solve_maect(nx.complete_graph(8))
    assert result.objective == pytest.approx(7.0, abs=1e-6)
    np.testing.assert_allclose(list(result.weights.values()), 1 / 28, atol=1e-9)


def test_cycle_c64_objective_is_n_n_plus_1_over_6():
    result = solve_maect(nx.cycle_graph(64))
    assert result.objective == pytest.approx(64 * 65 / 6, rel=1e-9)  # 693.33
    np.testing.assert_allclose(list(result.weights.values()), 1 / 64, atol=1e-9)


def test_line_of_20_matches_the_tree_closed_form():
    line = nx.path_graph(20)
    result = solve_maect(line)
    weights, objective = tree_optimum(line)
    assert objective == pytest.approx(126.8162, abs=1e-4)
    assert result.objective == pytest.approx(objective, rel=1e-9)
    k = np.arange(1, 20)
    expected = np.sqrt(k * (20 - k)) / np.sqrt(k * (20 - k)).sum()
    assert np.abs(np.array([result.weights[(i - 1, i)] for i in k]) - expected).max() < 1e-5


def test_random_tree_of_30_matches_the_closed_form():
    tree = nx.random_labeled_tree(30, seed=7)
    result = solve_maect(tree)
    weights, objective = tree_optimum(tree)
    assert result.objective == pytest.approx(objective, rel=1e-9)
    assert max(abs(result.weights[e] - w) for e, w in weights.items()) < 1e-5


def test_small_graph_optimum_of_the_cvx_example():
    result = solve_maect(small_graph())
    assert result.objective == pytest.approx(9.313075, abs=1e-5)
    np.testing.assert_allclose([result.weights[e] for e in SMALL_EDGES], SMALL_OPTIMUM, atol=1e-4)
    assert sum(result.weights.values()) == pytest.approx(1.0, abs=1e-12)


def test_cvxpy_cross_check_agrees_with_the_gradient_solver():
    pytest.importorskip("cvxpy")
    graph = small_graph()
    gradient, sdp = solve_maect(graph), solve_maect(graph, solver="cvxpy")
    assert sdp.objective == pytest.approx(gradient.objective, abs=1e-5)
    np.testing.assert_allclose([sdp.weights[e] for e in SMALL_EDGES],
                               [gradient.weights[e] for e in SMALL_EDGES], atol=1e-4)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_true_mean_commute_time_is_twice_the_printed_objective(seed):
    rng = np.random.default_rng(seed)
    graph = nx.connected_watts_strogatz_graph(12, 4, 0.3, seed=seed)
    w = rng.uniform(0.05, 1.0, graph.number_of_edges())
    w /= w.sum()
    weights = dict(zip(graph.edges(), w, strict=True))
    P, nodes = transition_matrix(graph, weights)
    objective = maect_objective(incidence(graph, nodes), w)
    assert mean_commute_time(P) == pytest.approx(2 * objective, rel=1e-8)


def test_optimum_beats_random_feasible_weights_and_the_walk_matches_it():
    graph = small_graph()
    result = solve_maect(graph)
    A = incidence(graph, result.nodes, result.edges)
    rng = np.random.default_rng(11)
    for _ in range(20):
        assert maect_objective(A, rng.dirichlet(np.ones(13))) >= result.objective - 1e-12
    assert mean_commute_time(result.transition) == pytest.approx(2 * result.objective, rel=1e-8)


def test_disconnecting_weights_give_an_infinite_objective():
    graph = nx.path_graph(3)
    assert maect_objective(incidence(graph), [1.0, 0.0]) == float("inf")


def test_simplex_projection():
    np.testing.assert_allclose(project_simplex(np.array([0.2, 0.3, 0.5])), [0.2, 0.3, 0.5])
    np.testing.assert_allclose(project_simplex(np.array([2.0, 0.0, -1.0])), [1.0, 0.0, 0.0])
    np.testing.assert_allclose(project_simplex(np.array([1.0, 1.0])), [0.5, 0.5])


def test_bad_inputs_are_named():
    with pytest.raises(ConfigError, match="solver"):
        solve_maect(nx.path_graph(3), solver="newton")
    with pytest.raises(ConfigError, match="graph"):
        solve_maect(nx.empty_graph(3))
    with pytest.raises(ConfigError, match="w"):
        laplacian(incidence(nx.path_graph(3)), [1.0])
