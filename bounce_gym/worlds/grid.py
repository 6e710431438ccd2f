"""Worlds made of unit cells: the grid maps of the cell-mapping papers.

A grid map is a boolean array ``free[row, col]`` with **row 0 at the bottom** (y points up), the
same layout `World.occupancy` returns. Cell ``(row, col)`` is the square
``[col*s, (col+1)*s] x [row*s, (row+1)*s]``, so with ``cell_size = 1`` its centre is
``(col + 0.5, row + 0.5)`` and ``World.occupancy(1.0)`` gives the grid back exactly.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.errors import InvalidWorldError
from bounce_gym.worlds.world import World


def world_from_grid(free: np.ndarray, cell_size: float = 1.0, name: str | None = None) -> World:
    """Build the free-space polygon of a grid of free cells.

    The rings are traced straight from the grid (`_boundary_rings`): no polygon union, so the
    time grows with the number of boundary edges, not with the number of holes times anything
    (a 1200 x 1200 map with 160,000 holes loads in seconds). Every ring keeps only its corners;
    the holes are sorted by their lowest, then leftmost vertex (bottom to top, then left to
    right), so equal grids give equal worlds — the same vertices, in the same order, as the
    union of the free cells gave before.

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
    rings, outer = _boundary_rings(grid)
    if outer.sum() != 1:
        raise InvalidWorldError(
            f"grid: free cells form {int(outer.sum())} separate regions; a world must be connected"
        )
    k = int(np.flatnonzero(outer)[0])
    holes = [cell_size * r for r in rings[:k] + rings[k + 1:]]
    return World(cell_size * rings[k], holes, name=name)


def _boundary_rings(grid: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The boundary rings of the free cells (cell units) and which of them are outer rings.

    The boundary edges (`_boundary_edges`) form disjoint cycles; each is labelled by its lowest,
    then leftmost vertex, ordered from the edge leaving that vertex (`_cycles`) and cut down to
    its corners. A ring starts one corner after that vertex (a lone rectangle: at it) — the
    order the former polygon union left in the world — and the rings come sorted by it.
    """
    start, step = _boundary_edges(grid)
    width = grid.shape[1] + 1
    start_id = start[:, 1] * width + start[:, 0]
    leaving = np.empty((grid.shape[0] + 1) * width, dtype=np.int64)
    leaving[start_id] = np.arange(len(start_id))
    label, rank = _cycles(start_id, leaving[start_id + step[:, 1] * width + step[:, 0]], leaving)
    order = np.lexsort((-rank, label))
    label, start, step = label[order], start[order], step[order]
    new_ring = np.r_[True, label[1:] != label[:-1]]
    ring_start = np.flatnonzero(new_ring)
    previous = np.arange(len(label)) - 1
    previous[ring_start] = np.r_[ring_start[1:], len(label)] - 1
    kept = np.flatnonzero(np.any(step != step[previous], axis=1))  # the corners
    bounds = np.searchsorted((np.cumsum(new_ring) - 1)[kept], np.arange(len(ring_start) + 1))
    index = np.arange(len(kept))
    if len(ring_start) > 1 or len(kept) > 4:  # the union gave back a lone box as it was built
        index = index + 1  # each ring from its second corner on, the first one last
        index[bounds[1:] - 1] = bounds[:-1]
    points = start[kept[index]].astype(np.float64)
    outer = step[ring_start, 0] == 1  # a ring leaves its lowest-leftmost vertex east iff CCW
    return np.split(points, bounds[1:-1]), outer


def _boundary_edges(grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every unit edge between a free and a blocked cell (or the outside): its start vertex
    (x, y) and unit step, directed with the free cell on its left, so outer rings run
    counter-clockwise and holes clockwise."""
    pad = np.zeros((grid.shape[0] + 2, grid.shape[1] + 2), dtype=bool)
    pad[1:-1, 1:-1] = grid
    below, above = pad[:-1, 1:-1], pad[1:, 1:-1]  # the cells under and over y = row
    left, right = pad[1:-1, :-1], pad[1:-1, 1:]  # the cells left and right of x = col
    starts, steps = [], []
    for edges, (dx, dy), (ox, oy) in (
        (above & ~below, (1, 0), (0, 0)),  # east along y = row, free above
        (left & ~right, (0, 1), (0, 0)),  # north along x = col, free on the left
        (below & ~above, (-1, 0), (1, 0)),  # west, free below
        (right & ~left, (0, -1), (0, 1)),  # south, free on the right
    ):
        row, col = np.nonzero(edges)
        starts.append(np.column_stack((col + ox, row + oy)))
        steps.append(np.broadcast_to((dx, dy), (len(row), 2)))
    return np.concatenate(starts), np.concatenate(steps)


def _cycles(start_id: np.ndarray, nxt: np.ndarray, leaving: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """For edges that form disjoint cycles (``nxt``: each edge's successor; without diagonal
    pinches every boundary vertex has one edge in and one out): each edge's cycle label, the
    smallest start vertex id of its cycle, and its rank, the steps from it to the cycle's last
    edge when the cycle starts at the edge leaving that vertex (``leaving``: vertex -> edge).
    Both by pointer doubling: O(edges x log(longest cycle))."""
    label, jump = start_id, nxt
    while True:  # a round that changes no label: every window spans its whole cycle
        merged = np.minimum(label, label[jump])
        if np.array_equal(merged, label):
            break
        label, jump = merged, jump[jump]
    last = nxt == leaving[label]  # the edge before the cycle's first
    rank = (~last).astype(np.int64)
    jump = np.where(last, np.arange(len(nxt)), nxt)
    while not np.array_equal(jump, jump[jump]):
        rank, jump = rank + rank[jump], jump[jump]
    return label, rank


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
