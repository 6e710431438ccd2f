"""Generalized cell mapping (GCM): persistent groups, domiciles, absorption and limiting coverage.

The GCM of the bouncing robot with unreliable rotation (Alam, Bobadilla & Shell, "Minimalist robot
navigation and coverage using a dynamical system approach", IRC 2017, Alg. 3
POLICYDISTRIBUTION; thesis §3.3.3 and Alg. 3.3, §5 Alg. 5.1) is a finite Markov chain on the
cells. ``P`` is **row-stochastic**: ``P[i, j] = Pr(i -> j)`` and distributions are row vectors,
``p(n+1) = p(n) P`` (the papers' ``p(n+1) = 𝒫 p(n)`` with the same p_ij; docs/choices/navigation_coverage.md, "The chain
is a row-vector chain").

Definitions (Hsu; thesis Defs. 3.3.1-3.3.3 and §5.4):

* i **leads to** j (i => j) iff p_ij^(k) > 0 for some k > 0; i and j **communicate** iff i => j and
  j => i;
* **persistent cell**: started in it, the chain returns to it with probability 1;
* **transient cell**: a cell that is not persistent; it leads to a persistent group;
* **persistent group**: a set of cells that is **closed** under the mapping (no probability
  leaves it) and in which every cell communicates with every other: an irreducible sub-chain.
  These are the strongly connected components with no outgoing edge (sinks of the condensation),
  **not** every strongly connected component (the papers' "reachable from all other vertices"
  test holds for every SCC; Alam, Bobadilla & Shell 2017, Sec. IV-C, thesis §5.4.3; docs/choices/navigation_coverage.md,
  "Persistent groups without a transitive closure");
* **domicile** of a transient cell: a persistent group it leads to; single- and
  multiple-domicile cells (thesis §5.4);
* **absorption probabilities** ``a = (I - Q)^-1 R`` (transient block Q, R summed per group) and
  **expected absorption times** ``t = (I - Q)^-1 1`` (Isaacson & Madsen; thesis Thm 5.4.3).

Limiting distribution (docs/choices/navigation_coverage.md, "The limiting distribution starts anywhere"). A chain with
several persistent groups, or a periodic one, has no plain limit of p(0) P^n, so the coverage is the
**Cesàro limit** ``π = lim (1/n) Σ_{k<n} p(0) P^k = Σ_g w_g π_g`` where π_g is the stationary
distribution of group g (π_g P_g = π_g, Σ π_g = 1; unique because P_g is irreducible, periodic or
not) and ``w_g = p(0)(g) + p(0)_T a[:, g]`` is the probability of ending in g. Modes for p(0):

* ``"all"`` (default): uniform over all N cells, "starting from any location":
  ``w_g = (|g| + Σ_{t∈T} a_{t,g}) / N``;
* ``"persistent"``: uniform over the persistent cells, ``w_g = |g| / Σ_h |h|``;
* ``"group"``: equal weight per group, ``w_g = 1 / n_groups``;
* or any (N,) probability vector p(0).

Everything is sparse: strong components from `scipy.sparse.csgraph`, one sparse LU
(`scipy.sparse.linalg.splu`) of the block-diagonal stationary system of all groups, and one of
(I - Q). No transitive closure and no (N, N) dense array; the weights of the default mode need a
single transposed solve ``(I - Q)^T y = p(0)_T`` rather than the full absorption matrix. The
absorption matrix (n_transient x n_groups, dense), the absorption times and the domiciles are
computed on first access.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components
from scipy.sparse.linalg import splu

from bounce_gym.errors import ConfigError
from bounce_gym.markov.ordering import grid_dissection

if TYPE_CHECKING:
    from bounce_gym.cells import CellModel, DrifterCells

__all__ = ["MODES", "GCMResult", "gcm", "generalized_cell_mapping", "layer_gcm"]

#: Initial distributions of the limiting distribution (see the module docstring).
MODES = ("all", "persistent", "group")
_ROW_TOL = 1e-9
_ABSORPTION_CHUNK = 64  # right-hand sides per LU solve in `GCMResult.absorption`


@dataclass(eq=False)
class GCMResult:
    """Persistent groups and the long-run behaviour of a row-stochastic cell map.

    Attributes:
        P: (N, N) CSR, the transition matrix (explicit zeros removed).
        group_of: (N,) int32, the persistent group 0..n_groups-1 of every cell; -1 if transient.
        groups: ``groups[g]`` = sorted cells of persistent group g; groups are numbered by
            increasing smallest cell.
        transient: sorted transient cells; row i of `absorption` is cell ``transient[i]``.
        stationary: (N,) the stationary distributions of all groups side by side: on group g it
            is π_g (summing to 1 over g), 0 on transient cells.
        weights: (n_groups,) w_g, the probability of ending in each group under ``mode``.
        limiting: (N,) π = Σ_g w_g π_g, the Cesàro-limit (long-run) distribution under ``mode``.
        mode: the initial distribution of ``weights`` / ``limiting``: a name in `MODES`, or
            ``"custom"`` for a given p(0).
        component: (N,) the strongly connected component of every cell (None if unknown).
        order: (N,) a fill-reducing order of the cells for the sparse LU of I - Q, or None for
            SuperLU's own (COLAMD).
    """

    P: sp.csr_matrix
    group_of: np.ndarray
    groups: list[np.ndarray]
    transient: np.ndarray
    stationary: np.ndarray
    weights: np.ndarray
    limiting: np.ndarray
    mode: str
    component: np.ndarray | None = None
    order: np.ndarray | None = None

    @property
    def n_cells(self) -> int:
        return self.P.shape[0]

    @property
    def n_groups(self) -> int:
        return len(self.groups)

    @property
    def persistent(self) -> np.ndarray:
        """(N,) bool, True for persistent cells."""
        return self.group_of >= 0

    @property
    def sizes(self) -> np.ndarray:
        """(n_groups,) number of cells of each persistent group."""
        return np.array([len(g) for g in self.groups], dtype=np.int64)

    @cached_property
    def transient_index(self) -> np.ndarray:
        """(N,) row of each transient cell in `absorption`, -1 for persistent cells."""
        index = np.full(self.n_cells, -1, dtype=np.int64)
        index[self.transient] = np.arange(len(self.transient))
        return index

    def stationary_of(self, g: int) -> np.ndarray:
        """π_g on the cells ``groups[g]`` (π_g P_g = π_g, Σ = 1)."""
        return self.stationary[self.groups[g]]

    # -- transient analysis (lazy) ----------------------------------------------------------
    @cached_property
    def _to_groups(self) -> sp.csr_matrix:
        """R summed per group: (n_transient, n_groups), Pr(t -> group g) in one step."""
        pers = np.flatnonzero(self.group_of >= 0)
        member = sp.csr_matrix((np.ones(len(pers)), (pers, self.group_of[pers])),
                               shape=(self.n_cells, self.n_groups))
        return (self.P[self.transient] @ member).tocsr()

    @cached_property
    def _solver(self):
        return _transient_lu(self.P, self.transient, self.order)

    @cached_property
    def absorption(self) -> np.ndarray:
        """(n_transient, n_groups) dense, ``a[i, g]`` = probability that the chain started in
        ``transient[i]`` is absorbed into group g: ``a = (I - Q)^-1 R 1_g``. Rows sum to 1."""
        n_t = len(self.transient)
        out = np.empty((n_t, self.n_groups))
        if n_t == 0:
            return out
        rhs = self._to_groups.tocsc()
        for start in range(0, self.n_groups, _ABSORPTION_CHUNK):
            stop = min(start + _ABSORPTION_CHUNK, self.n_groups)
            out[:, start:stop] = self._solver.solve(rhs[:, start:stop].toarray())
        return np.clip(out, 0.0, 1.0, out=out)

    @cached_property
    def absorption_time(self) -> np.ndarray:
        """(n_transient,) expected number of steps before a chain started in ``transient[i]``
        enters a persistent group: ``t = (I - Q)^-1 1`` (thesis Thm 5.4.3)."""
        if len(self.transient) == 0:
            return np.zeros(0)
        return self._solver.solve(np.ones(len(self.transient)))

    @cached_property
    def domiciles(self) -> sp.csr_matrix:
        """(n_transient, n_groups) bool CSR: entry (i, g) iff ``transient[i]`` leads to group g.

        Exact reachability, not a threshold on `absorption`: one breadth-first search per group
        on the reversed graph of the transient strongly connected components (every cell of a
        component reaches the same groups)."""
        n_t, n_g = len(self.transient), self.n_groups
        if n_t == 0 or n_g == 0:
            return sp.csr_matrix((n_t, n_g), dtype=bool)
        component = self.component
        if component is None:
            _, component = connected_components(self.P, directed=True, connection="strong")
        # number the transient components 0..k-1
        comp_ids, comp = np.unique(component[self.transient], return_inverse=True)
        k = len(comp_ids)
        q = self.P[self.transient][:, self.transient].tocoo()
        r = self._to_groups.tocoo()
        src = np.concatenate((comp[q.row], comp[r.row]))
        dst = np.concatenate((comp[q.col], r.col + k))
        keep = src != dst
        # reversed condensed graph: u -> c iff c -> u
        rev = sp.csr_matrix((np.ones(int(keep.sum()), dtype=np.int8), (dst[keep], src[keep])),
                            shape=(k + n_g, k + n_g))
        pair_comp, pair_group = [], []
        for g in range(n_g):
            reach = breadth_first_order(rev, k + g, directed=True, return_predecessors=False)
            reach = reach[reach < k]
            pair_comp.append(reach)
            pair_group.append(np.full(len(reach), g))
        pair_comp, pair_group = np.concatenate(pair_comp), np.concatenate(pair_group)
        # expand (component, group) pairs to (cell, group) entries
        by_comp = np.argsort(comp, kind="stable")
        starts = np.searchsorted(comp[by_comp], np.arange(k))
        counts = np.bincount(comp, minlength=k)
        reps = counts[pair_comp]
        offsets = np.repeat(starts[pair_comp] - np.cumsum(reps) + reps, reps)
        rows = by_comp[np.arange(int(reps.sum())) + offsets]
        cols = np.repeat(pair_group, reps)
        return sp.csr_matrix((np.ones(len(rows), dtype=bool), (rows, cols)), shape=(n_t, n_g))

    def domiciles_of(self, z: int) -> tuple[int, ...]:
        """The persistent groups cell z can be absorbed into (its own group if persistent)."""
        if self.group_of[z] >= 0:
            return (int(self.group_of[z]),)
        i = self.transient_index[z]
        d = self.domiciles
        return tuple(int(g) for g in d.indices[d.indptr[i]:d.indptr[i + 1]])

    def domicile_groups(self) -> dict[frozenset[int], np.ndarray]:
        """Transient cells grouped by their domicile set (thesis §5.4 'transient groups'):
        single-domicile sets {g} are the domains of attraction B(g), larger sets the boundary
        regions B(g, h, ...). Sets are ordered by size, then by their sorted groups; cells
        ascending."""
        d = self.domiciles
        d.sort_indices()
        counts = np.diff(d.indptr)
        out: dict[frozenset[int], np.ndarray] = {}
        for size in np.unique(counts):  # rows with `size` domiciles: an (n, size) index table
            rows = np.flatnonzero(counts == size)
            table = np.ascontiguousarray(d.indices[d.indptr[rows][:, None] + np.arange(size)],
                                         dtype=np.int32)
            # one opaque key per row: rows of equal bytes are equal sets (indices are sorted)
            _, first, inverse = np.unique(table.view(np.dtype((np.void, 4 * size))).ravel(),
                                          return_index=True, return_inverse=True)
            keys = table[first]
            by_key = np.argsort(inverse, kind="stable")
            splits = np.cumsum(np.bincount(inverse, minlength=len(keys)))[:-1]
            for key, members in zip(keys, np.split(rows[by_key], splits), strict=True):
                out[frozenset(key.tolist())] = self.transient[members]
        return dict(sorted(out.items(), key=lambda kv: (len(kv[0]), sorted(kv[0]))))

    # -- limiting distribution --------------------------------------------------------------
    def group_weights(self, start: str | np.ndarray = "all") -> np.ndarray:
        """w_g, the probability of ending in each group from the initial distribution ``start``
        (a name in `MODES` or an (N,) probability vector)."""
        n = self.n_cells
        if isinstance(start, str):
            if start not in MODES:
                raise ConfigError(f"mode: expected one of {MODES} or an (N,) array, got {start!r}")
            if start == "group":
                return np.full(self.n_groups, 1.0 / self.n_groups)
            sizes = self.sizes.astype(np.float64)
            if start == "persistent":
                return sizes / sizes.sum()
            p0 = None  # uniform over all cells
        else:
            p0 = np.asarray(start, dtype=np.float64)
            if p0.shape != (n,) or not np.all(np.isfinite(p0)) or np.any(p0 < 0) \
                    or abs(p0.sum() - 1.0) > 1e-9:
                raise ConfigError(f"start: expected a probability vector of shape ({n},)")
        if p0 is None:
            direct = self.sizes / n
            p0_t = np.full(len(self.transient), 1.0 / n)
        else:
            pers = np.flatnonzero(self.group_of >= 0)
            direct = np.bincount(self.group_of[pers], weights=p0[pers], minlength=self.n_groups)
            p0_t = p0[self.transient]
        if len(self.transient) == 0 or not p0_t.any():
            return direct
        # Σ_t p0_t a[t, :] = y^T R with (I - Q)^T y = p0_T: one solve instead of n_groups
        y = self._solver.solve(p0_t, trans="T")
        return direct + self._to_groups.T @ y

    def limiting_distribution(self, start: str | np.ndarray = "all") -> np.ndarray:
        """(N,) the Cesàro limit Σ_g w_g π_g for the initial distribution ``start``."""
        return _mix(self.stationary, self.group_of, self.group_weights(start))


def generalized_cell_mapping(P, mode: str | np.ndarray = "all",
                             order: np.ndarray | None = None) -> GCMResult:
    """Persistent groups, stationary distributions and the limiting distribution of ``P``.

    Args:
        P: (N, N) row-stochastic matrix (scipy sparse, or a dense array for small cases).
        mode: initial distribution of ``weights`` / ``limiting``: ``"all"`` (uniform over all
            cells, docs/choices/navigation_coverage.md, "The limiting distribution starts anywhere"), ``"persistent"``,
            ``"group"``, or an (N,) probability vector.
        order: optional permutation of the N cells to eliminate I - Q in (a fill-reducing
            order such as `bounce_gym.markov.ordering.grid_dissection` of cells on a grid);
            None lets SuperLU choose (COLAMD).

    Raises:
        ConfigError: P is not square, has negative or non-finite entries, or a row that does not
            sum to 1 (within 1e-9).
    """
    P = _check_stochastic(P)
    n = P.shape[0]
    if order is not None:
        order = np.asarray(order)
        if order.shape != (n,) or order.dtype.kind not in "iu" or not np.array_equal(
                np.sort(order), np.arange(n)):
            raise ConfigError(f"order: expected a permutation of the {n} cells")
    if isinstance(mode, str) and mode not in MODES:
        raise ConfigError(f"mode: expected one of {MODES} or an (N,) array, got {mode!r}")
    # strongly connected components; closed ones (no edge leaving) are the persistent groups
    n_scc, labels = connected_components(P, directed=True, connection="strong")
    src = np.repeat(np.arange(n), np.diff(P.indptr))
    leaving = labels[src] != labels[P.indices]
    is_open = np.zeros(n_scc, dtype=bool)
    is_open[labels[src[leaving]]] = True
    del src, leaving
    persistent = ~is_open[labels]
    pers = np.flatnonzero(persistent)
    # number the groups by their smallest cell (pers is ascending, so first occurrence)
    closed_labels, first = np.unique(labels[pers], return_index=True)
    by_first = np.argsort(pers[first], kind="stable")
    group_of_label = np.full(n_scc, -1, dtype=np.int32)
    group_of_label[closed_labels[by_first]] = np.arange(len(by_first), dtype=np.int32)
    group_of = np.full(n, -1, dtype=np.int32)
    group_of[pers] = group_of_label[labels[pers]]
    sizes = np.bincount(group_of[pers], minlength=len(by_first))
    by_group = pers[np.argsort(group_of[pers], kind="stable")]
    groups = np.split(by_group, np.cumsum(sizes)[:-1]) if len(by_first) else []
    transient = np.flatnonzero(~persistent)

    stationary = _stationary(P, pers, group_of[pers], groups)
    result = GCMResult(P=P, group_of=group_of, groups=groups, transient=transient,
                       stationary=stationary, weights=np.zeros(len(groups)),
                       limiting=np.zeros(n), mode="custom" if not isinstance(mode, str) else mode,
                       component=labels, order=order)
    result.weights = result.group_weights(mode)
    result.limiting = _mix(stationary, group_of, result.weights)
    return result


def gcm(model: CellModel, phi: float, eps: float = 0.0, r: float = 1.0,
        mode: str | np.ndarray = "all") -> GCMResult:
    """The GCM analysis of ``model.transition_matrix(phi, eps, r)`` (angles in radians, r the
    probability of the nominal rotation)."""
    return generalized_cell_mapping(model.transition_matrix(phi, eps, r), mode=mode)


def layer_gcm(model: DrifterCells, layer: int, mode: str | np.ndarray = "all") -> GCMResult:
    """The GCM analysis of one layer of a drifter model (thesis Alg. 5.1 PERSISTENTBEHAVIOR):
    persistent groups, transient groups by domicile set (`GCMResult.domicile_groups`),
    absorption times and probabilities. Cell k of the result is state
    ``model.offsets[layer] + k``. I - Q is eliminated in the nested-dissection order of the
    layer's grid (`grid_dissection`), which keeps the sparse LU of a 10^6-cell layer small."""
    cells = model.cells[model.layer_states(layer)]
    order = grid_dissection(cells[:, 1], cells[:, 2], width=2)
    return generalized_cell_mapping(model.transition_matrix(layer), mode=mode, order=order)


# -- internals --------------------------------------------------------------------------------
def _check_stochastic(P) -> sp.csr_matrix:
    if sp.issparse(P):
        P = sp.csr_matrix(P, dtype=np.float64, copy=True)
    else:
        dense = np.asarray(P, dtype=np.float64)
        if dense.ndim != 2:
            raise ConfigError(f"P: expected a 2-D matrix, got shape {dense.shape}")
        P = sp.csr_matrix(dense)
    if P.shape[0] != P.shape[1] or P.shape[0] == 0:
        raise ConfigError(f"P: expected a non-empty square matrix, got shape {P.shape}")
    if not np.all(np.isfinite(P.data)) or np.any(P.data < 0):
        raise ConfigError("P: entries must be finite and >= 0")
    P.sum_duplicates()
    P.eliminate_zeros()  # explicit zeros are not transitions
    rows = np.asarray(P.sum(axis=1)).ravel()
    bad = np.flatnonzero(np.abs(rows - 1.0) > _ROW_TOL)
    if len(bad):
        raise ConfigError(f"P: rows must sum to 1; row {bad[0]} sums to {rows[bad[0]]!r} "
                          f"({len(bad)} bad rows)")
    return P


def _stationary(P: sp.csr_matrix, pers: np.ndarray, gid: np.ndarray,
                groups: list[np.ndarray]) -> np.ndarray:
    """π_g of every group from one sparse LU of the block-diagonal system.

    For each group: π_g (I - P_g) = 0 with the equation of its smallest cell replaced by Σ π_g = 1.
    (I - P_g) has rank |g| - 1 with left null space spanned by π_g > 0 (P_g irreducible, periodic
    or not), and its columns' only dependency is their sum, so the replaced system is regular.
    """
    n = P.shape[0]
    out = np.zeros(n)
    if len(pers) == 0:
        return out
    local = np.full(n, -1, dtype=np.int64)
    local[pers] = np.arange(len(pers))
    sub = P[pers][:, pers].tocoo()  # closed groups: no entry crosses between groups
    # row i of A = column i of (I - P_sub): A = I - P_sub^T
    rows = np.concatenate((np.arange(len(pers)), sub.col))
    cols = np.concatenate((np.arange(len(pers)), sub.row))
    vals = np.concatenate((np.ones(len(pers)), -sub.data))
    root_rows = local[np.array([g[0] for g in groups])]
    is_root_row = np.zeros(len(pers), dtype=bool)
    is_root_row[root_rows] = True
    keep = ~is_root_row[rows]
    # normalisation rows: the smallest cell's row becomes the indicator of its group
    rows = np.concatenate((rows[keep], root_rows[gid]))
    cols = np.concatenate((cols[keep], np.arange(len(pers))))
    vals = np.concatenate((vals[keep], np.ones(len(pers))))
    A = sp.csc_matrix((vals, (rows, cols)), shape=(len(pers), len(pers)))
    b = np.zeros(len(pers))
    b[root_rows] = 1.0
    pi = splu(A).solve(b)
    pi = np.maximum(pi, 0.0)  # round-off only: the exact solution is > 0
    pi /= np.bincount(gid, weights=pi)[gid]
    out[pers] = pi
    return out


def _transient_lu(P: sp.csr_matrix, transient: np.ndarray, order: np.ndarray | None = None):
    """Sparse LU of (I - Q), Q the transient-to-transient block (regular: every transient cell
    leads to a persistent group, so Q^n -> 0).

    With a cell ``order``, the transient cells are eliminated in that order without pivoting:
    I - Q is a nonsingular M-matrix, whose Gaussian elimination keeps positive pivots."""
    q = P[transient][:, transient]
    eye = sp.identity(len(transient), format="csc")
    if order is None:
        return splu((eye - q).tocsc())
    position = np.full(P.shape[0], -1, dtype=np.int64)
    position[transient] = np.arange(len(transient))
    perm = position[order]
    perm = perm[perm >= 0]
    lu = splu((eye - q)[perm][:, perm].tocsc(), permc_spec="NATURAL", diag_pivot_thresh=0.0,
              options=dict(SymmetricMode=True))
    return _PermutedLU(lu, perm)


class _PermutedLU:
    """``solve`` of A from the LU of A[perm][:, perm]."""

    def __init__(self, lu, perm: np.ndarray) -> None:
        self.lu, self.perm = lu, perm

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        out = np.empty_like(b, dtype=np.float64)
        out[self.perm] = self.lu.solve(np.ascontiguousarray(b[self.perm]), trans=trans)
        return out


def _mix(stationary: np.ndarray, group_of: np.ndarray, weights: np.ndarray) -> np.ndarray:
    out = np.zeros(len(stationary))
    pers = group_of >= 0
    out[pers] = stationary[pers] * weights[group_of[pers]]
    return out
