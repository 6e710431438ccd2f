"""MAECT for a vertex subset, the "clique" problem 4.5 (Alam 2018, thesis §4.4.1), on the small
graph of thesis §4.5.2 with Q = {v2, v5, v8} as in Table 4.2."""

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.game import payoff_matrices, preferred_all, preferred_subset
from baselines.patrolling.maect import solve_maect
from baselines.patrolling.markov import hitting_times, transition_matrix
from baselines.patrolling.subset import (
    DEFAULT_CYCLE_SHARE,
    cycle_order,
    project_subset_simplex,
    solve_subset_maect,
    subset_cycle_edges,
)
from bounce_gym.errors import ConfigError

CLIQUE = [2, 5, 8]
UNCONSTRAINED_OPTIMUM = 9.313075


def ranking(graph, result, preferred) -> list:
    """Vertices (1-based labels) ranked by Alg. 4.2 on the preferred hitting time (ascending,
    near-ties in index order)."""
    nodes = sorted(graph)
    P, _ = transition_matrix(graph, result.weights, nodes)
    payoff, _ = payoff_matrices(preferred(hitting_times(P))[None, :])
    return [nodes[i] for i in np.argsort(-payoff[0])]


def test_shortest_cycle_of_the_clique(cvx_small_graph):
    # 2 -> 5 ties between 2-1-5 and 2-7-5 (both 1 + √1.25); the smaller sequence wins
    edges = subset_cycle_edges(cvx_small_graph, CLIQUE)
    assert {frozenset(e) for e in edges} == {frozenset(e) for e in
                                             [(1, 2), (1, 5), (2, 8), (5, 7), (7, 8)]}
    assert subset_cycle_edges(cvx_small_graph, [8, 5, 2]) == edges


@pytest.mark.parametrize("h", [0.5, DEFAULT_CYCLE_SHARE, 0.95])
def test_cycle_share_and_objective_bound(cvx_small_graph, h):
    result = solve_subset_maect(cvx_small_graph, CLIQUE, h=h)
    on_cycle = sum(result.weights[e] for e in subset_cycle_edges(cvx_small_graph, CLIQUE))
    assert on_cycle >= h - 1e-9
    assert sum(result.weights.values()) == pytest.approx(1.0, abs=1e-12)
    assert min(result.weights.values()) >= 0
    assert result.objective >= UNCONSTRAINED_OPTIMUM - 1e-9


def test_full_share_needs_a_cycle_through_every_vertex(cvx_small_graph):
    ring = solve_subset_maect(nx.cycle_graph(6), [0, 2, 4], h=1.0)
    assert ring.objective == pytest.approx(6 * 7 / 6, rel=1e-9)  # C_6, uniform weights
    with pytest.raises(ConfigError, match="h"):
        solve_subset_maect(cvx_small_graph, CLIQUE, h=1.0)


def test_a_loose_share_gives_the_unconstrained_optimum(cvx_small_graph):
    free = solve_maect(cvx_small_graph)
    share = sum(free.weights[e] for e in subset_cycle_edges(cvx_small_graph, CLIQUE))
    loose = solve_subset_maect(cvx_small_graph, CLIQUE, h=share - 0.01)
    assert loose.objective == pytest.approx(UNCONSTRAINED_OPTIMUM, abs=1e-5)


@pytest.mark.parametrize(("h", "objective"), [(0.75, 12.43), (0.8, 14.35)])
def test_table_4_2_clique_and_maect_rankings(cvx_small_graph, h, objective):
    result = solve_subset_maect(cvx_small_graph, CLIQUE, h=h)
    assert result.objective == pytest.approx(objective, abs=5e-3)
    nodes = sorted(cvx_small_graph)
    subset = [nodes.index(v) for v in CLIQUE]
    assert ranking(cvx_small_graph, result, lambda H: preferred_subset(H, subset)) == [
        8, 2, 5, 1, 7, 4, 6, 3]
    maect = solve_maect(cvx_small_graph)
    # v3 and v8 tie by a symmetry of the graph; the tie keeps index order
    assert ranking(cvx_small_graph, maect, preferred_all) == [7, 2, 5, 3, 8, 1, 4, 6]


@pytest.mark.parametrize("h", [0.6, 0.9])
def test_other_shares_do_not_give_the_clique_ranking(cvx_small_graph, h):
    result = solve_subset_maect(cvx_small_graph, CLIQUE, h=h)
    subset = [sorted(cvx_small_graph).index(v) for v in CLIQUE]
    assert ranking(cvx_small_graph, result, lambda H: preferred_subset(H, subset)) != [
        8, 2, 5, 1, 7, 4, 6, 3]


def test_cvxpy_cross_check(cvx_small_graph):
    pytest.importorskip("cvxpy")
    gradient = solve_subset_maect(cvx_small_graph, CLIQUE)
    sdp = solve_subset_maect(cvx_small_graph, CLIQUE, solver="cvxpy")
    assert sdp.objective == pytest.approx(gradient.objective, abs=2e-3)
    assert sdp.objective >= gradient.objective - 1e-9
    np.testing.assert_allclose([sdp.weights[e] for e in sdp.edges],
                               [gradient.weights[e] for e in gradient.edges], atol=1e-3)


@pytest.mark.parametrize("scaled", [False, True])
def test_projection_is_the_nearest_feasible_point(scaled):
    rng = np.random.default_rng(5)
    mask = np.array([True, True, False, False, False])
    for _ in range(20):
        v = rng.normal(size=5)
        scale = rng.uniform(0.01, 1.0, 5) if scaled else np.ones(5)
        w = project_subset_simplex(v, mask, 0.7, scale if scaled else None)
        assert w.min() >= 0 and w.sum() == pytest.approx(1.0) and w[mask].sum() >= 0.7 - 1e-12

        def distance(x, v=v, scale=scale):
            return float(np.sum((x - v) ** 2 / scale))

        for _ in range(50):  # no feasible point is closer
            other = rng.dirichlet(np.ones(5))
            if other[mask].sum() >= 0.7:
                assert distance(other) >= distance(w) - 1e-12


def test_tsp_order_of_five_vertices_on_a_grid():
    grid = nx.grid_2d_graph(6, 6)
    nx.set_edge_attributes(grid, 1.0, "length")
    corners = [(0, 0), (5, 5), (0, 5), (5, 0), (0, 2)]  # a tour around the border
    order = cycle_order(grid, corners)
    assert order[0] == (0, 0) and sorted(order) == sorted(corners)
    around = [(0, 0), (0, 2), (0, 5), (5, 5), (5, 0)]
    assert order in (around, [around[0], *around[:0:-1]])
    edges = subset_cycle_edges(grid, corners)
    assert len(edges) == 20  # the border of the 6 x 6 grid
    assert all(min(u[0], v[0]) in (0, 5) or min(u[1], v[1]) in (0, 5) for u, v in edges)


def test_bad_inputs_are_named(cvx_small_graph):
    for h in (0.0, 1.5, -0.2, "0.8"):
        with pytest.raises(ConfigError, match="h"):
            solve_subset_maect(cvx_small_graph, CLIQUE, h=h)
    with pytest.raises(ConfigError, match="subset"):
        subset_cycle_edges(cvx_small_graph, [2, 9])
    with pytest.raises(ConfigError, match="subset"):
        subset_cycle_edges(cvx_small_graph, [2])
    with pytest.raises(ConfigError, match="subset"):
        subset_cycle_edges(cvx_small_graph, [2, 2, 5])
    split = nx.Graph([(0, 1), (2, 3)])
    with pytest.raises(ConfigError, match="subset"):
        subset_cycle_edges(split, [0, 2])
