"""Random walks on a patrol graph (Alam 2018, thesis §4.4.1): the transition matrix of edge
weights, first hitting times and commute times.

Matrices are row-stochastic, ``P[i, j] = Pr(i -> j)``, over the vertices in the order ``nodes``
returned with them. A hitting time is ``inf`` when the walk, started at i, misses the target with
positive probability (a reducible chain such as those of thesis Alg. 4.1); nothing is raised.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence

import networkx as nx
import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph
import scipy.sparse.linalg as spla

from bounce_gym.errors import ConfigError

__all__ = ["commute_times", "hitting_times", "mean_commute_time", "transition_matrix"]


def _edge_weight(weights: Mapping, u: Hashable, v: Hashable) -> float:
    if (u, v) in weights:
        return float(weights[(u, v)])
    if (v, u) in weights:
        return float(weights[(v, u)])
    raise ConfigError(f"weights: no weight for edge {(u, v)!r}")


def transition_matrix(graph: nx.Graph, weights: Mapping | None = None,
                      nodes: Sequence | None = None) -> tuple[sp.csr_array, list]:
    """The weighted random walk ``P[i, j] = w_ij / sum_k w_ik`` (no self-loops).

    Args:
        graph: an undirected graph.
        weights: edge (u, v) -> weight >= 0, either orientation; None for the simple random walk.
        nodes: the vertex order of the matrix (default: ``list(graph)``).

    Returns:
        (P, nodes).
    """
    nodes = list(graph) if nodes is None else list(nodes)
    if set(nodes) != set(graph) or len(nodes) != graph.number_of_nodes():
        raise ConfigError("nodes: expected every vertex of the graph exactly once")
    index = {v: i for i, v in enumerate(nodes)}
    rows, cols, vals = [], [], []
    for u, v in graph.edges():
        w = 1.0 if weights is None else _edge_weight(weights, u, v)
        if not np.isfinite(w) or w < 0:
            raise ConfigError(f"weights: expected finite weights >= 0, got {w!r} on {(u, v)!r}")
        rows += [index[u], index[v]]
        cols += [index[v], index[u]]
        vals += [w, w]
    n = len(nodes)
    w_matrix = sp.csr_array((vals, (rows, cols)), shape=(n, n))
    degree = np.asarray(w_matrix.sum(axis=1)).ravel()
    if np.any(degree <= 0):
        stuck = nodes[int(np.flatnonzero(degree <= 0)[0])]
        raise ConfigError(f"weights: vertex {stuck!r} has no edge of positive weight")
    return sp.csr_array(sp.diags_array(1.0 / degree) @ w_matrix), nodes


def hitting_times(P, targets: Sequence[int] | None = None) -> np.ndarray:
    """Expected first hitting times ``H[i, j]`` of target j from i (``H[j, j] = 0``).

    Args:
        P: (n, n) row-stochastic matrix, dense or sparse.
        targets: column indices to compute (default: all).

    Returns:
        (n, len(targets)) array; ``inf`` where the target is missed with positive probability.
    """
    P = sp.csr_array(P, dtype=np.float64)
    n = P.shape[0]
    if P.shape != (n, n):
        raise ConfigError(f"P: expected a square matrix, got shape {P.shape}")
    if (P.data < 0).any() or not np.allclose(P.sum(axis=1), 1.0, atol=1e-9):
        raise ConfigError("P: expected a row-stochastic matrix (entries >= 0, rows summing to 1)")
    targets = range(n) if targets is None else list(targets)
    support = sp.csr_array((P > 0).astype(np.int8))
    out = np.full((n, len(targets)), np.inf)
    for col, j in enumerate(targets):
        # the walk is stopped at j: drop j's outgoing arcs
        stopped = support.tolil()
        stopped.rows[j], stopped.data[j] = [], []
        reverse = sp.csr_array(stopped.tocsr().T)
        reaches_j = _reachable_from(reverse, [j])
        missing = np.flatnonzero(~reaches_j)
        # any state that can walk into a state that never reaches j misses j with positive prob.
        lost = _reachable_from(reverse, missing) if len(missing) else np.zeros(n, dtype=bool)
        finite = np.flatnonzero(~lost)
        finite = finite[finite != j]
        out[j, col] = 0.0
        if len(finite):
            block = P[finite][:, finite]
            system = sp.identity(len(finite), format="csc") - sp.csc_array(block)
            out[finite, col] = spla.spsolve(system, np.ones(len(finite)))
    return out


def _reachable_from(reverse: sp.csr_array, sources) -> np.ndarray:
    """Vertices with a path to any of ``sources`` (searched in the reversed graph)."""
    n = reverse.shape[0]
    seen = np.zeros(n, dtype=bool)
    for s in sources:
        if not seen[s]:
            order = csgraph.breadth_first_order(reverse, int(s), directed=True,
                                                return_predecessors=False)
            seen[order] = True
    return seen


def commute_times(P) -> np.ndarray:
    """Expected commute times ``C[i, j] = H[i, j] + H[j, i]``."""
    H = hitting_times(P)
    return H + H.T


def mean_commute_time(P) -> float:
    """Mean of ``C[i, j]`` over ordered pairs i != j (``inf`` if any pair is unreachable)."""
    C = commute_times(P)
    n = C.shape[0]
    if n < 2:
        raise ConfigError(f"P: a commute time needs at least 2 states, got {n}")
    return float(C[~np.eye(n, dtype=bool)].mean())
