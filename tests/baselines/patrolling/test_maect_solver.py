"""The MAECT gradient solver's pieces: the Cholesky objective and gradient, and the certified
duality-gap bound it stops on (thesis problem 4.4)."""

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.maect import (
    _objective_and_gradient,
    _projected_gradient,
    _relative_gap,
    incidence,
    maect_objective,
    solve_maect,
)
from bounce_gym.errors import ConfigError


def test_objective_matches_the_eigenvalues_and_the_gradient_finite_differences():
    graph = nx.connected_watts_strogatz_graph(15, 4, 0.3, seed=1)
    A = incidence(graph)
    w = np.random.default_rng(0).dirichlet(np.ones(A.shape[1]))
    f, g = _objective_and_gradient(A, w)
    assert f == pytest.approx(maect_objective(A, w), rel=1e-12)
    assert -g @ w == pytest.approx(f, rel=1e-12)  # homogeneous of degree -1
    h = 1e-6
    for e in (0, 7, A.shape[1] - 1):
        step = np.zeros_like(w)
        step[e] = h
        numeric = (_objective_and_gradient(A, w + step)[0]
                   - _objective_and_gradient(A, w - step)[0]) / (2 * h)
        assert g[e] == pytest.approx(numeric, rel=1e-6)


def test_disconnecting_weights_have_an_infinite_objective():
    A = incidence(nx.path_graph(4))
    f, g = _objective_and_gradient(A, np.array([0.5, 0.0, 0.5]))
    assert f == float("inf") and not g.any()


def test_the_gap_bounds_the_distance_to_a_known_optimum():
    """On a tree the optimum is known in closed form (thesis Fig. 4.5): the certified bound is
    never below the true relative gap, at random weights and along the solver's path."""
    tree = nx.random_labeled_tree(25, seed=3)
    n = 25
    total = 0.0
    for u, v in tree.edges():
        cut = tree.copy()
        cut.remove_edge(u, v)
        side = len(nx.node_connected_component(cut, u))
        total += np.sqrt(side * (n - side))
    optimum = 2.0 / (n * (n - 1)) * total**2
    A = incidence(tree)
    rng = np.random.default_rng(5)
    for w in [*rng.dirichlet(np.ones(n - 1), 20), np.full(n - 1, 1 / (n - 1))]:
        f, g = _objective_and_gradient(A, w)
        bound = _relative_gap(f, g.min())
        assert (f - optimum) / f <= bound + 1e-12
        assert bound > 1e-3  # and not trivially small away from the optimum
    for tol in (1e-3, 1e-6, 1e-10):
        w, _ = _projected_gradient(A, tol, 10_000)
        f = _objective_and_gradient(A, w)[0]
        assert -1e-14 <= (f - optimum) / f <= tol + 1e-14


def test_the_returned_weights_meet_the_requested_gap_and_the_limit_is_named():
    graph = nx.grid_2d_graph(5, 6)
    result = solve_maect(graph, tol=1e-9)
    A = incidence(graph, result.nodes, result.edges)
    f, g = _objective_and_gradient(A, np.array(list(result.weights.values())))
    assert _relative_gap(f, g.min()) <= 1e-9
    with pytest.raises(ConfigError, match="max_iter"):
        solve_maect(graph, tol=1e-12, max_iter=2)
