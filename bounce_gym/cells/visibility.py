"""Limited-range visibility of grid cells, VISIBLECELLS of Alg. 4.3 (Alam 2018, thesis ch. 4,
§4.3.3, Eq. 4.1), and the watch regions T, ∂V(x_z), T' of a target cell (§4.3.5).

A grid map is a boolean array ``free[row, col]`` with row 0 at the bottom, as in
`bounce_gym.worlds.grid`; cell ``(row, col)`` is the unit square with centre
``(col + 0.5, row + 0.5)`` and the blocked cells are the obstacles. Cells are numbered in
row-major order of the free cells (``np.flatnonzero(free)``). Ranges are in cell units.

VISIBLECELLS (rule ``"corners"``): cell c is seen from the centre x_z of cell z when c lies
completely inside the limited visibility polygon V(x_z) of Eq. 4.1 as far as its corners and
centre tell: all four corners of c are within l of x_z, and the segments from x_z to the centre
and to the four corners of c (each corner pulled ε into c) do not cross the interior of a
blocked cell. Rule ``"centre"`` only asks for the centre within l and the centre segment clear;
it is symmetric (z sees c iff c sees z). The segment tests use shapely.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import shapely

from bounce_gym import validate
from bounce_gym.errors import ConfigError

__all__ = ["RULES", "CellVisibility", "WatchRegion", "cell_visibility", "watch_region"]

#: When a cell counts as seen: corners in range and corner-and-centre line of sight, or the
#: centre alone.
RULES = ("corners", "centre")

_EPS = 1e-6
_CORNERS = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])


@dataclass(frozen=True, eq=False)
class CellVisibility:
    """VISIBLECELLS for every free cell of a grid map.

    Attributes:
        cells: (n, 2) int64, ``(row, col)`` of the free cells in their index order.
        seen: (n, n) bool CSR, entry (z, c) iff a robot at the centre of cell z sees cell c.
        l: the sensing range in cells.
        rule: the visibility rule (one of `RULES`).
    """

    cells: np.ndarray
    seen: sp.csr_matrix
    l: float  # noqa: E741 (the thesis' name for the range)
    rule: str

    def __len__(self) -> int:
        return len(self.cells)

    def visible_from(self, z: int) -> np.ndarray:
        """The indices of the cells seen from cell ``z``, ascending."""
        z = validate.integer("z", z, 0, len(self) - 1)
        return self.seen.indices[self.seen.indptr[z]:self.seen.indptr[z + 1]].copy()


def _grid(free: object) -> np.ndarray:
    grid = np.asarray(free)
    if grid.ndim != 2 or grid.size == 0:
        raise ConfigError(f"free: expected a non-empty 2-D array, got shape {grid.shape}")
    if grid.dtype != bool:
        if grid.dtype.kind not in "iu" or not np.isin(grid, (0, 1)).all():
            raise ConfigError("free: cells must be booleans (True/1 = free, False/0 = blocked)")
        grid = grid.astype(bool)
    if not grid.any():
        raise ConfigError("free: the grid has no free cell")
    return grid


def cell_visibility(free: object, l: float, rule: str = "corners") -> CellVisibility:  # noqa: E741
    """VISIBLECELLS(V(x_z)) of Alg. 4.3 (line 2) for every free cell z of the grid ``free``.

    Raises:
        ConfigError: ``free`` is not a non-empty boolean grid with a free cell, ``l`` is not a
            number > 0, or ``rule`` is not one of `RULES`.
    """
    grid = _grid(free)
    l = validate.number("l", l, minimum=0.0, strict=True)  # noqa: E741
    if rule not in RULES:
        raise ConfigError(f"rule: expected one of {RULES}, got {rule!r}")
    rows, cols = np.nonzero(grid)
    cells = np.column_stack((rows, cols)).astype(np.int64)
    n = len(cells)
    index = np.full(grid.shape, -1, dtype=np.int64)
    index[rows, cols] = np.arange(n)
    centres = cells[:, ::-1] + 0.5  # (x, y)
    # candidate offsets (dy, dx) whose far corner (or centre) is within range
    span = math.ceil(l)
    dy, dx = np.mgrid[-span:span + 1, -span:span + 1]
    pad = 0.5 if rule == "corners" else 0.0
    near = np.hypot(np.abs(dx) + pad, np.abs(dy) + pad) <= l
    dy, dx = dy[near], dx[near]
    src = np.repeat(np.arange(n), len(dy))
    tr, tc = rows[src] + np.tile(dy, n), cols[src] + np.tile(dx, n)
    inside = (tr >= 0) & (tr < grid.shape[0]) & (tc >= 0) & (tc < grid.shape[1])
    src, tr, tc = src[inside], tr[inside], tc[inside]
    dst = index[tr, tc]
    src, dst = src[dst >= 0], dst[dst >= 0]
    clear = _clear(grid, centres[src], centres[dst], src != dst, rule)
    src, dst = src[clear], dst[clear]
    seen = sp.csr_matrix((np.ones(len(src), dtype=bool), (src, dst)), shape=(n, n))
    seen.sort_indices()
    return CellVisibility(cells=cells, seen=seen, l=l, rule=rule)


def _clear(grid: np.ndarray, origins: np.ndarray, centres: np.ndarray, other: np.ndarray,
           rule: str) -> np.ndarray:
    """Whether the segments from each origin to the target cell's centre (and, for
    ``"corners"``, its four corners pulled ε inward) miss the interiors of the blocked cells."""
    blocked_r, blocked_c = np.nonzero(~grid)
    clear = np.ones(len(origins), dtype=bool)
    if len(blocked_r) == 0:
        return clear
    obstacles = shapely.unary_union(shapely.box(blocked_c, blocked_r, blocked_c + 1, blocked_r + 1))
    shapely.prepare(obstacles)
    ends = [centres]
    if rule == "corners":
        ends += [centres + corner * (1 - 2 * _EPS) for corner in _CORNERS]
    test = np.flatnonzero(other)  # a cell always sees itself
    for end in ends:
        todo = test[clear[test]]
        lines = shapely.linestrings(np.stack((origins[todo], end[todo]), axis=1))
        crosses = shapely.relate_pattern(lines, obstacles, "T********")
        clear[todo[crosses]] = False
    return clear


@dataclass(frozen=True, eq=False)
class WatchRegion:
    """The cells around a target cell z used in the vulnerability evaluation (thesis §4.3.5).

    Attributes:
        target: the target cell z.
        inside: T, the cells seen from z (inside V(x_z)), ascending.
        boundary: ∂V(x_z), the cells of T that are 8-adjacent to a free cell outside T.
        outside: T', the free cells not in T.
    """

    target: int
    inside: np.ndarray
    boundary: np.ndarray
    outside: np.ndarray


def watch_region(visibility: CellVisibility, z: int) -> WatchRegion:
    """T, ∂V(x_z) and T' for target cell ``z``; ∂V(x_z) is read as the cells of T first
    reached from T' by an 8-neighbour move.

    Raises:
        ConfigError: ``z`` is not a cell index of ``visibility``.
    """
    if not isinstance(visibility, CellVisibility):
        raise ConfigError(f"visibility: expected a CellVisibility, got "
                          f"{type(visibility).__name__}")
    inside = visibility.visible_from(z)
    n = len(visibility)
    in_t = np.zeros(n, dtype=bool)
    in_t[inside] = True
    rows, cols = visibility.cells.T
    shape = (rows.max() + 3, cols.max() + 3)  # one cell of margin on each side
    outside_grid = np.zeros(shape, dtype=bool)
    outside_grid[rows[~in_t] + 1, cols[~in_t] + 1] = True
    near_outside = np.zeros(n, dtype=bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                near_outside |= outside_grid[rows + 1 + dr, cols + 1 + dc]
    return WatchRegion(target=int(z), inside=inside,
                       boundary=np.flatnonzero(in_t & near_outside),
                       outside=np.flatnonzero(~in_t))
