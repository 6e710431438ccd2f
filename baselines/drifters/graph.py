"""Reachability on the support graph of a cell chain (i -> j iff p_ij > 0), the "leads to"
relation of Alam 2018, thesis §5.4.3, computed without a transitive closure: a breadth-first
search from a set of cells, and the source strongly connected components of a subgraph."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components

__all__ = ["reachable", "source_components", "support"]


def support(P) -> sp.csr_matrix:
    """The (N, N) int8 CSR adjacency of the nonzero entries of ``P`` (explicit zeros dropped)."""
    P = sp.csr_matrix(P)
    P.eliminate_zeros()
    return sp.csr_matrix((np.ones(P.nnz, dtype=np.int8), P.indices, P.indptr), shape=P.shape)


def reachable(P, starts, reverse: bool = False) -> np.ndarray:
    """(N,) bool: the cells reachable from any of ``starts`` (which count as reached) along the
    nonzero entries of ``P``; with ``reverse``, the cells from which a start is reachable.

    One breadth-first search (`scipy.sparse.csgraph.breadth_first_order`) from an extra node
    joined to every start."""
    A = support(P)
    n = A.shape[0]
    starts = np.unique(np.asarray(starts, dtype=np.int64).ravel())
    out = np.zeros(n, dtype=bool)
    if len(starts) == 0:
        return out
    if reverse:
        A = A.T.tocsr()
    a = A.tocoo()
    rows = np.concatenate((a.row, np.full(len(starts), n)))
    cols = np.concatenate((a.col, starts))
    graph = sp.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(n + 1, n + 1))
    order = breadth_first_order(graph, n, directed=True, return_predecessors=False)
    out[order[order < n]] = True
    return out


def source_components(P, cells) -> list[np.ndarray]:
    """The source strongly connected components of the subgraph of ``P`` induced on ``cells``:
    the components no other cell of ``cells`` leads into. Each is a sorted array of cells;
    the list is ordered by smallest cell. Every cell of ``cells`` is reachable, inside the
    subgraph, from a source component, and no source component from any other cell."""
    cells = np.sort(np.asarray(cells, dtype=np.int64))
    if len(cells) == 0:
        return []
    sub = support(sp.csr_matrix(P)[cells][:, cells]).tocoo()
    n, label = connected_components(sub, directed=True, connection="strong")
    entered = np.zeros(n, dtype=bool)
    across = label[sub.row] != label[sub.col]
    entered[label[sub.col[across]]] = True
    comps = [cells[label == k] for k in np.flatnonzero(~entered)]
    return sorted(comps, key=lambda c: int(c[0]))
