"""Simple cell mapping (SCM): periodic groups, transient cells and their steps to the cycle.

This is Algorithm 1, MODIFIEDSIMPLECELLMAPPING, of Alam, Bobadilla & Shell, "Space-efficient
filters for mobile robot localization from discrete limit cycles" (IEEE RA-L 2018; thesis
Algorithm 2.1), with its index errors fixed (docs/choices/cell_model.md, "Algorithm 1's index errors and order
independence") and the cell loop replaced by whole-array
operations, so that the paper's simulation scale (200 x 125 positions x 360 bins, about 9 M cells)
is analysed in seconds.

Definitions (paper Defs. 1-4, thesis Defs. 2.3.1-2.3.4), for the simple cell map
e(i+1) = C(e(i)) given by ``successor[z] = C(z)``:

* **periodic cell**: z = C^m(z) for some m >= 1 (its period is the least such m);
* **transient cell**: a cell that is not periodic; it maps into a periodic cell in a finite number
  of steps;
* **periodic group** (attractor, limit cycle) of period K: K distinct cells e(1..K) with
  e(m+1) = C^m(e(1)) for m = 1..K-1 and e(1) = C^K(e(1));
* **transient trajectory** of a periodic group: the cells that finally lead to it; the collection
  of transient trajectories is the **basin of attraction**.

In Hsu's SCM every cell has exactly one domicile, its group ``group[z]``.

How the index errors are resolved (docs/choices/cell_model.md, "Algorithm 1's index errors and order
independence"):

* the walk of lines 7-12 uses its own cursor, never the loop variable ``i``;
* ``d``, undefined in the paper, is the position in the walk where the cycle closes, so the
  period is K = k - d; line 23 loops over ``j``;
* line 27 adds the cells to the transient set of group ``g_z`` (the paper writes ``T_r``);
* ``NEXTCELL`` is evaluated from the centre of the current cell (the caller's successor array).

The array formulation computes the same g, s and groups without the sequential walk, so nothing
depends on the order in which cells are visited:

* C is a functional graph (out-degree 1). Its periodic cells are the cells of its strongly
  connected components of size > 1 plus the fixed points, found by
  `scipy.sparse.csgraph.connected_components` (``connection="strong"``). Each such component is
  one cycle, i.e. one periodic group; every weakly connected component holds exactly one of them.
* The steps s_z to the periodic group, and the periodic cell where z enters it, come from pointer
  doubling (``O(N log max s)``), with periodic cells as terminals; z's group is its entry cell's
  group.
* The cycle order comes from pointer doubling too, with the smallest cell of each cycle as the
  terminal: a cell d steps before the smallest cell sits at position K - d of the cycle.

Groups are numbered 0..r-1 by increasing smallest periodic cell, and each cycle is listed in the
order of C starting at its smallest cell (a deterministic numbering; the paper fixes none).

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from bounce_gym.errors import ConfigError

if TYPE_CHECKING:
    from bounce_gym.cells import CellModel

__all__ = ["SCMResult", "scm", "simple_cell_mapping"]


@dataclass(eq=False)
class SCMResult:
    """The periodic groups and transient trajectories of a simple cell map.

    Attributes:
        successor: (N,) the map C, ``successor[z] = C(z)`` (the array given, unchanged).
        group: (N,) int32, the group index 0..r-1 of every cell (its single domicile).
        periodic: (N,) bool, True for periodic cells (Def. 1), False for transient ones (Def. 2).
        steps: (N,) int32, s_z = number of mappings to reach the periodic group; 0 on the cycle.
        n_groups: r, the number of periodic groups (Def. 3).
        cycles: r arrays; ``cycles[g]`` lists the periodic cells of group g in the order of C,
            starting at its smallest cell, so ``successor[cycles[g][j]] == cycles[g][j + 1]``.
        periods: (r,) the period K of each group (``len(cycles[g])``).
        max_transient: max_z s_z, the longest transient trajectory (Sec. V-A;
            docs/choices/cell_model.md, "Longest transient trajectory").
        bump: (N,) bool or None, the observation of each step (True = bump, label 1) when known.
    """

    successor: np.ndarray
    group: np.ndarray
    periodic: np.ndarray
    steps: np.ndarray
    n_groups: int
    cycles: list[np.ndarray]
    periods: np.ndarray
    max_transient: int
    bump: np.ndarray | None = None

    @property
    def n_cells(self) -> int:
        """N, the number of cells."""
        return len(self.successor)

    @property
    def transient(self) -> np.ndarray:
        """(N,) bool, True for transient cells (Def. 2)."""
        return ~self.periodic

    def period_of(self, z: np.ndarray | int) -> np.ndarray:
        """The period of the group that cell(s) ``z`` end in."""
        return self.periods[self.group[z]]

    def basin(self, g: int) -> np.ndarray:
        """Sorted cells of group g, periodic and transient: the P_g ∪ T_g of Algorithm 1, i.e.
        the vertices of its I-state graph (BUILD-STATEGRAPH)."""
        return np.flatnonzero(self.group == g)

    def transient_trajectory(self, g: int) -> np.ndarray:
        """Sorted transient cells that lead to group g (Def. 4; the T_g of Algorithm 1)."""
        return np.flatnonzero((self.group == g) & ~self.periodic)


def simple_cell_mapping(successor: np.ndarray, bump: np.ndarray | None = None) -> SCMResult:
    """Analyse the simple cell map ``C(z) = successor[z]`` (cells 0..N-1).

    Args:
        successor: (N,) integer array with values in 0..N-1. Fixed points (period 1) are allowed,
            although the bouncing robot's map has none.
        bump: optional (N,) bool observations, stored on the result for the I-state graphs.

    Returns:
        An `SCMResult`; see the module docstring for the definitions and the numbering.

    Raises:
        ConfigError: ``successor`` is not a non-empty 1-D integer array of cells, or ``bump`` has
            the wrong shape.
    """
    succ_in = _check_successor(successor)
    n = len(succ_in)
    if bump is not None:
        bump = np.asarray(bump, dtype=bool)
        if bump.shape != (n,):
            raise ConfigError(f"bump: expected shape ({n},), got {bump.shape}")
    idx = np.int32 if n < np.iinfo(np.int32).max else np.int64
    succ = succ_in.astype(idx, copy=False)
    cells = np.arange(n, dtype=idx)

    # periodic cells: strongly connected components of size > 1, plus fixed points
    graph = sp.csr_matrix((np.ones(n, dtype=np.int8), succ, np.arange(n + 1, dtype=idx)),
                          shape=(n, n))
    _, labels = connected_components(graph, directed=True, connection="strong")
    del graph
    periodic = np.bincount(labels)[labels] > 1
    periodic |= succ == cells

    # one group per periodic component, numbered by its smallest cell
    pc = np.flatnonzero(periodic).astype(idx, copy=False)
    pc_labels = labels[pc]
    del labels
    smallest = np.full(int(pc_labels.max()) + 1, n, dtype=idx)
    np.minimum.at(smallest, pc_labels, pc)
    roots = np.unique(smallest[pc_labels])  # sorted smallest cell of each cycle
    n_groups = len(roots)
    group_of_label = np.full(len(smallest), -1, dtype=np.int32)
    group_of_label[pc_labels[np.searchsorted(pc, roots)]] = np.arange(n_groups, dtype=np.int32)
    group = np.full(n, -1, dtype=np.int32)
    group[pc] = group_of_label[pc_labels]
    del pc_labels, smallest, group_of_label
    periods = np.bincount(group[pc], minlength=n_groups).astype(np.int64)

    # cycle order: steps from each periodic cell forward to its group's smallest cell
    is_root = np.zeros(n, dtype=bool)
    is_root[roots] = True
    to_root, _ = _pointer_jump(succ, is_root | ~periodic, pc[~is_root[pc]])
    del is_root
    period_pc = periods[group[pc]]
    position = (period_pc - to_root[pc]) % period_pc
    del to_root, period_pc
    ordered = pc[np.lexsort((position, group[pc]))]
    cycles = np.split(ordered, np.cumsum(periods)[:-1])
    del position, ordered

    # transient cells: steps to the periodic group and the cell where they enter it
    steps, entry = _pointer_jump(succ, periodic, np.flatnonzero(~periodic).astype(idx, copy=False))
    group = group[entry]
    del entry
    return SCMResult(
        successor=succ_in,
        group=group,
        periodic=periodic,
        steps=steps,
        n_groups=n_groups,
        cycles=cycles,
        periods=periods,
        max_transient=int(steps.max()),
        bump=bump,
    )


def scm(model: CellModel, phi: float) -> SCMResult:
    """Algorithm 1 for a cell model and bounce angle ``phi`` (radians): the SCM of
    ``model.successor(phi)``, with the bump observations attached."""
    succ, bump = model.successor(phi)
    return simple_cell_mapping(succ, bump=bump)


# -- internals --------------------------------------------------------------------------------
def _check_successor(successor: np.ndarray) -> np.ndarray:
    succ = np.asarray(successor)
    if succ.ndim != 1 or len(succ) == 0:
        raise ConfigError(f"successor: expected a non-empty 1-D array, got shape {succ.shape}")
    if not np.issubdtype(succ.dtype, np.integer):
        raise ConfigError(f"successor: expected an integer array, got dtype {succ.dtype}")
    lo, hi = int(succ.min()), int(succ.max())
    if lo < 0 or hi >= len(succ):
        raise ConfigError(
            f"successor: cells must be in 0..{len(succ) - 1}, got values in {lo}..{hi}"
        )
    return succ


def _pointer_jump(succ: np.ndarray, terminal: np.ndarray,
                  active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Steps from each ``active`` cell along ``succ`` to the first ``terminal`` cell, and that
    cell, by pointer doubling.

    Every active cell must reach a terminal cell through active cells only. Terminal and other
    cells get 0 steps and point to themselves. Invariant: ``ptr[z] = C^dist[z](z)`` and no cell
    strictly between z and ``ptr[z]`` is terminal; each round doubles the jump.
    """
    n = len(succ)
    dist = np.zeros(n, dtype=succ.dtype)
    ptr = np.arange(n, dtype=succ.dtype)
    dist[active] = 1
    ptr[active] = succ[active]
    active = active[~terminal[ptr[active]]]
    while active.size:
        hop = ptr[active]
        dist[active] += dist[hop]
        beyond = ptr[hop]
        ptr[active] = beyond
        active = active[~terminal[beyond]]
    return dist, ptr
