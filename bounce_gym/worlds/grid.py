"""Worlds made of unit cells: the grid maps of the cell-mapping papers.

A grid map is a boolean array ``free[row, col]`` with **row 0 at the bottom** (y points up), the
same layout `World.occupancy` returns. Cell ``(row, col)`` is the square
``[col*s, (col+1)*s] x [row*s, (row+1)*s]``, so with ``cell_size = 1`` its centre is
``(col + 0.5, row + 0.5)`` and ``World.occupancy(1.0)`` gives the grid back exactly.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon

from bounce_gym.errors import InvalidWorldError
from bounce_gym.worlds.world import World


def world_from_grid(free: np.ndarray, cell_size: float = 1.0, name: str | None = None) -> World:
    """Build the free-space polygon of a grid of free cells.

    Every ring starts at its lowest, then leftmost vertex, and the holes are sorted by that vertex
    (bottom to top, then left to right), so equal grids give equal worlds.

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
    if not grid.any():
        raise InvalidWorldError("grid: has no free cell")
    x0, y0, x1, y1 = (cell_size * v for v in _free_rectangles(grid))
    union = shapely.unary_union(shapely.box(x0, y0, x1, y1))
    if not isinstance(union, Polygon):
        raise InvalidWorldError(
            f"grid: free cells form {len(union.geoms)} separate regions; a world must be connected"
        )
    union = union.simplify(0)  # drop the collinear vertices between rectangles
    # holes in a fixed order (by the lowest, then leftmost vertex), not the union's arbitrary one
    holes = sorted((_canonical(h.coords) for h in union.interiors), key=lambda h: (h[0, 1], h[0, 0]))
    return World(_canonical(union.exterior.coords), holes, name=name)


def _free_rectangles(grid: np.ndarray) -> tuple[np.ndarray, ...]:
    """The free cells as few axis-aligned rectangles ``(col0, row0, col1, row1)`` (cell units).

    Each row splits into maximal runs of free cells; runs with the same columns in consecutive
    rows merge into one rectangle. Unioning these instead of single cells gives the same
    polygon, with far fewer pieces for the polygon union (a 3000 x 3000 map loads in well
    under a second).
    """
    pad = np.zeros((grid.shape[0], grid.shape[1] + 2), dtype=np.int8)
    pad[:, 1:-1] = grid
    step = np.diff(pad, axis=1)
    row, c0 = np.nonzero(step == 1)  # row-major order, so the k-th start pairs with the k-th end
    c1 = np.nonzero(step == -1)[1]
    order = np.lexsort((row, c1, c0))  # the runs of one column span, bottom to top
    row, c0, c1 = row[order], c0[order], c1[order]
    new = np.ones(len(row), dtype=bool)
    new[1:] = (c0[1:] != c0[:-1]) | (c1[1:] != c1[:-1]) | (row[1:] != row[:-1] + 1)
    first = np.flatnonzero(new)
    last = np.append(first[1:], len(row)) - 1
    return c0[first], row[first], c1[first], row[last] + 1


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
    text = "".join(rows_top_first)
    codes = np.frombuffer(text.encode("utf-32-le"), dtype=np.uint32)
    free = codes == ord(".")
    if not np.all(free | (codes == ord("#"))):
        bad = set(text) - {".", "#"}
        raise InvalidWorldError(
            f"grid: unknown cell characters {sorted(bad)}; allowed are '.' (free) and '#' (blocked)"
        )
    return free.reshape(len(rows_top_first), -1)[::-1].copy()


def to_ascii(free: np.ndarray) -> list[str]:
    """Inverse of `parse_ascii`."""
    codes = np.where(np.asarray(free, dtype=bool)[::-1], ord("."), ord("#")).astype(np.uint8)
    return [row.tobytes().decode("ascii") for row in codes]
