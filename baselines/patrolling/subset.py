"""MAECT for a subset of vertices, the "clique" problem (Alam 2018, thesis §4.4.1, problem 4.5).

The subset Q is tied together by ShortestCycle(Q): the union of shortest paths between
consecutive vertices of Q (for Q = {i, j, k}: SP(i, j) ∪ SP(j, k) ∪ SP(k, i)). Problem 4.5 keeps
the objective of eq. 4.3 and the simplex of problem 4.4 over all edges of the graph and adds that
the cycle's edges g carry at least the share h of the weight: ``sum_{e in g} w_e >= h``.

Where the thesis is open (docs/choices/patrolling.md, "The subset problem's share h = 0.8" and
"ShortestCycle of more than three vertices, and ties between shortest paths"):

* h is not given; the default 0.8 ranks the vertices of the thesis's small graph as the Clique
  row of Table 4.2 does (any h in [0.75, 0.80] does, 0.5-0.7 and >= 0.85 do not);
* the thesis only writes the cycle of three vertices; more than three are visited in the order
  of a Christofides tour (networkx) on the metric closure of Q;
* shortest paths use the edge attribute ``length`` (1 where missing); between equally short paths
  the lexicographically smallest vertex sequence, walked from the smaller end vertex, wins (on the
  small graph 2-1-5 rather than 2-7-5).
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence

import networkx as nx
import numpy as np

from baselines.patrolling.maect import MaectResult, _solve, project_simplex
from bounce_gym.errors import ConfigError

__all__ = ["DEFAULT_CYCLE_SHARE", "cycle_order", "project_subset_simplex", "solve_subset_maect",
           "subset_cycle_edges"]

#: h of problem 4.5: the share of the edge weight that the cycle through the subset carries.
DEFAULT_CYCLE_SHARE = 0.8
# relative length difference below which two paths count as equally short
_TIE = 1e-9


def _check_subset(graph: nx.Graph, subset: Sequence[Hashable]) -> list:
    subset = list(subset)
    missing = [v for v in subset if v not in graph]
    if missing:
        raise ConfigError(f"subset: vertices {missing!r} are not in the graph")
    if len(set(subset)) != len(subset) or len(subset) < 2:
        raise ConfigError(f"subset: expected at least 2 distinct vertices, got {subset!r}")
    return subset


def _distances(graph: nx.Graph, sources: Sequence[Hashable]) -> dict:
    """Shortest-path lengths (edge ``length``, 1 where missing) from each source."""
    return {s: nx.single_source_dijkstra_path_length(graph, s, weight="length") for s in sources}


def cycle_order(graph: nx.Graph, subset: Sequence[Hashable]) -> list:
    """The order in which ShortestCycle visits the subset: as given for up to three vertices (any
    order closes the same cycle), else a Christofides tour of the metric closure of the subset,
    started at its first vertex (the tour is a 3/2-approximation of the shortest one)."""
    subset = _check_subset(graph, subset)
    if len(subset) <= 3:
        return subset
    distance = _distances(graph, subset)
    if any(t not in distance[s] for s in subset for t in subset):
        raise ConfigError("subset: the vertices must lie in one connected component")
    closure = nx.Graph()
    closure.add_weighted_edges_from((s, t, distance[s][t]) for a, s in enumerate(subset)
                                    for t in subset[a + 1:])
    tour = nx.approximation.christofides(closure, weight="weight")[:-1]
    start = tour.index(subset[0])
    return tour[start:] + tour[:start]


def _tied_shortest_path(graph: nx.Graph, source: Hashable, target: Hashable,
                        to_target: dict) -> list:
    """The lexicographically smallest of the shortest source-target paths, walked greedily on the
    distances ``to_target``."""
    path = [source]
    while path[-1] != target:
        v = path[-1]
        slack = _TIE * max(1.0, to_target[v])
        path.append(min(u for u in graph[v] if u in to_target and abs(
            graph[v][u].get("length", 1) + to_target[u] - to_target[v]) <= slack))
    return path


def subset_cycle_edges(graph: nx.Graph, subset: Sequence[Hashable]) -> list:
    """The edges of ShortestCycle(Q) (thesis problem 4.5): the union of the shortest paths
    between consecutive vertices of `cycle_order`, in the order of ``graph.edges()``.

    Args:
        graph: an undirected graph; edge attribute ``length`` (1 where missing).
        subset: at least two distinct vertices of ``graph`` in one connected component.
    """
    order = cycle_order(graph, subset)
    distance = _distances(graph, order)
    used = set()
    for a, b in zip(order, order[1:] + order[:1], strict=True):
        source, target = min(a, b), max(a, b)
        if source not in distance[target]:
            raise ConfigError("subset: the vertices must lie in one connected component")
        path = _tied_shortest_path(graph, source, target, distance[target])
        used.update(frozenset(e) for e in zip(path, path[1:], strict=False))
    return [e for e in graph.edges() if frozenset(e) in used]


def project_subset_simplex(v: np.ndarray, mask: np.ndarray, h: float,
                           scale: np.ndarray | None = None) -> np.ndarray:
    """Projection of ``v`` onto {w >= 0, sum w = 1, sum w[mask] >= h}: Euclidean, or with
    ``scale`` (> 0) in the metric ``sum (w - v)² / scale``.

    The simplex projection already satisfies the share constraint, or the constraint is active at
    the projection; then the problem splits into two simplex projections, of ``v[mask]`` onto
    {sum = h} and of the rest onto {sum = 1 - h} (exact, no bisection)."""
    c = np.ones_like(v, dtype=np.float64) if scale is None else scale
    w = project_simplex(v, c)
    if w[mask].sum() >= h or mask.all():
        return w
    w = np.zeros_like(v, dtype=np.float64)
    w[mask] = h * project_simplex(v[mask] / h, c[mask])
    if h < 1.0:
        w[~mask] = (1.0 - h) * project_simplex(v[~mask] / (1.0 - h), c[~mask])
    return w


def solve_subset_maect(graph: nx.Graph, subset: Sequence[Hashable],
                       h: float = DEFAULT_CYCLE_SHARE, solver: str = "gradient",
                       tol: float = 1e-10, max_iter: int = 100_000) -> MaectResult:
    """Optimal edge weights of problem 4.5 (thesis §4.4.1): MAECT over all edges of ``graph``
    with at least the share ``h`` of the weight on the edges of ShortestCycle(subset).

    The gradient solver takes steps scaled by the weights (a diagonal metric): the few cycle
    edges carry most of the weight and the many others little, and plain steps need ten times as
    many iterations (2407 against 246 on a 10 x 10 grid with three subset vertices).

    Args:
        graph: an undirected connected graph; edge attribute ``length`` (1 where missing).
        subset: the vertices Q to favour, at least two distinct ones.
        h: the cycle's share of the weight, in (0, 1] (1 only when the cycle passes every
            vertex); default 0.8.
        solver: ``"gradient"`` (projected gradient, numpy) or ``"cvxpy"`` (SDP cross-check).
        tol: the gradient solver stops when its certified relative duality gap, an upper bound
            on ``(objective - optimum) / objective``, is at most ``tol``.
        max_iter: iteration limit of the gradient solver.
    """
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not 0.0 < h <= 1.0:
        raise ConfigError(f"h: expected a share in (0, 1], got {h!r}")
    cycle = {frozenset(e) for e in subset_cycle_edges(graph, subset)}
    if h == 1.0 and len(set().union(*cycle)) < graph.number_of_nodes():
        raise ConfigError("h: h = 1 leaves no weight for the vertices off ShortestCycle(subset); "
                          "expected h < 1")
    mask = np.array([frozenset(e) in cycle for e in graph.edges()])
    on_cycle = np.flatnonzero(mask)

    def project(v: np.ndarray, scale: np.ndarray | None) -> np.ndarray:
        return project_subset_simplex(v, mask, h, scale)

    def constraints(w) -> list:
        return [np.ones(len(on_cycle)) @ w[on_cycle] >= h]

    def lowest(g: np.ndarray) -> float:
        # the least gᵀv over the feasible set: the share h on the cycle's steepest edge, the
        # rest on the steepest edge overall
        return h * float(g[mask].min()) + (1.0 - h) * float(g.min())

    return _solve(graph, solver, tol, max_iter, project, constraints, scaled=True, lowest=lowest)
