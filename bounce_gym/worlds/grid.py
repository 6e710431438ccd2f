"""Worlds made of unit cells: the grid maps of the cell-mapping papers.

A grid map is a boolean array ``free[row, col]`` with **row 0 at the bottom** (y points up), the
same layout `World.occupancy` returns. Cell ``(row, col)`` is the square
``[col*s, (col+1)*s] x [row*s, (row+1)*s]``, so with ``cell_size = 1`` its centre is
``(col + 0.5, row + 0.5)`` and ``World.occupancy(1.0)`` gives the grid back exactly.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from bounce_gym.errors import InvalidWorldError
from bounce_gym.worlds.world import World


def world_from_grid(free: np.ndarray, cell_size: float = 1.0, name: str | None = None) -> World:
    """Build the free-space polygon of a grid of free cells.

    Raises:
        InvalidWorldError: no free cell, free cells not 4-connected, or a diagonal pinch (two
            free cells meeting only at a corner), which has no valid polygon.
    """
    grid = np.asarray(free)
    if grid.ndim != 2 or grid.size == 0:
        raise InvalidWorldError(f"grid: expected a non-empty 2-D array, got shape {grid.shape}")
    if grid.dtype != bool:
        if not np.isin(grid, (0, 1)).all():
            raise InvalidWorldError("grid: cells must be booleans (True/1 = free, False/0 = blocked)")
        grid = grid.astype(bool)
    if not np.isfinite(cell_size) or cell_size <= 0:
        raise InvalidWorldError(f"cell_size must be a finite number > 0, got {cell_size!r}")
    _check_pinches(grid)
    rows, cols = np.nonzero(grid)
    if len(rows) == 0:
        raise InvalidWorldError("grid: has no free cell")
    cells = [box(c * cell_size, r * cell_size, (c + 1) * cell_size, (r + 1) * cell_size)
             for r, c in zip(rows.tolist(), cols.tolist(), strict=True)]
    union = shapely.unary_union(cells)
    if not isinstance(union, Polygon):
        raise InvalidWorldError(
            f"grid: free cells form {len(union.geoms)} separate regions; a world must be connected"
        )
    union = union.simplify(0)  # drop the collinear vertices between cells
    rings = [_canonical(union.exterior.coords), *(_canonical(h.coords) for h in union.interiors)]
    return World(rings[0], rings[1:], name=name)


def _canonical(coords) -> np.ndarray:
    """A ring started at its bottom-most, then left-most vertex, so equality does not depend on
    the vertex order the polygon union happened to return."""
    ring = np.asarray(coords)[:-1]
    start = np.lexsort((ring[:, 0], ring[:, 1]))[0]
    return np.roll(ring, -start, axis=0)


def _check_pinches(grid: np.ndarray) -> None:
    a, b = grid[:-1, :-1], grid[1:, 1:]
    c, d = grid[:-1, 1:], grid[1:, :-1]
    pinch = (a & b & ~c & ~d) | (c & d & ~a & ~b)
    if np.any(pinch):
        r, col = (int(v) for v in np.argwhere(pinch)[0])
        raise InvalidWorldError(
            f"grid: free cells meet only at the corner between rows {r}-{r + 1} (counted from "
            f"the bottom) and columns {col}-{col + 1} (diagonal pinch); block or free one more "
            "cell there"
        )


def parse_ascii(rows_top_first: list[str]) -> np.ndarray:
    """Parse a picture of the map (top row first; ``.`` free, ``#`` blocked) to ``free[row, col]``."""
    if isinstance(rows_top_first, str) or not all(isinstance(r, str) for r in rows_top_first):
        raise InvalidWorldError("grid: expected a list of row strings (top row first)")
    if not rows_top_first:
        raise InvalidWorldError("grid: no rows")
    widths = {len(r) for r in rows_top_first}
    if len(widths) != 1:
        raise InvalidWorldError(f"grid: rows have different lengths {sorted(widths)}")
    bad = set("".join(rows_top_first)) - {".", "#"}
    if bad:
        raise InvalidWorldError(
            f"grid: unknown cell characters {sorted(bad)}; allowed are '.' (free) and '#' (blocked)"
        )
    return np.array([[ch == "." for ch in row] for row in reversed(rows_top_first)], dtype=bool)


def to_ascii(free: np.ndarray) -> list[str]:
    """Inverse of `parse_ascii`."""
    return ["".join("." if v else "#" for v in row) for row in np.asarray(free)[::-1]]
