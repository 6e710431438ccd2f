"""Segments near a point, for many points at once: a uniform grid whose cells list the segments
within a reach of them.

The bump table (`bounce_gym.dynamics.bump_table`) asks, for 10⁴ particles per update, which
boundary segment each contact point lies on and which walls it touches. Testing every point
against every segment costs (points × segments); the grid lists, per cell of side ``cell``, the
segments within ``reach`` of any point of the cell (padded to the longest list with a segment
far away), so each point is tested against its cell's few segments only. Points farther than
``reach`` from every segment may find none.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

#: where the padding segment lies: farther than any reach from any world
FAR = 1e30


class SegmentGrid:
    """The segments (``start``, ``end``: (m, 2)) within ``reach`` of each grid cell (module
    docstring)."""

    def __init__(self, start: np.ndarray, end: np.ndarray, cell: float, reach: float) -> None:
        start = np.asarray(start, dtype=np.float64).reshape(-1, 2)
        end = np.asarray(end, dtype=np.float64).reshape(-1, 2)
        low = np.minimum(start, end).min(axis=0) - reach
        high = np.maximum(start, end).max(axis=0) + reach
        self.cell, self.origin = float(cell), low
        self.shape = tuple(int(v) for v in np.maximum(np.ceil((high - low) / cell), 1))
        cols, rows = self.shape
        cx, cy = np.meshgrid(low[0] + (np.arange(cols) + 0.5) * cell,
                             low[1] + (np.arange(rows) + 0.5) * cell)
        centre = np.column_stack((cx.ravel(), cy.ravel()))  # row-major: index row * cols + col
        # the padding segment, index m, lies far away
        self.start = np.vstack((start, [FAR, FAR]))
        self.end = np.vstack((end, [FAR, FAR]))
        limit = reach + 0.5 * math.sqrt(2.0) * cell
        tree = shapely.STRtree(shapely.linestrings(np.stack((start, end), axis=1)))
        cell_of, segment = tree.query(shapely.points(centre), predicate="dwithin",
                                      distance=limit)
        order = np.lexsort((segment, cell_of))
        cell_of, segment = cell_of[order], segment[order]
        count = np.bincount(cell_of, minlength=len(centre))
        rank = np.arange(len(cell_of)) - np.repeat(np.cumsum(count) - count, count)
        self.near_table = np.full((len(centre), max(1, int(count.max(initial=0)))), len(start),
                                  dtype=np.int64)
        self.near_table[cell_of, rank] = segment

    def near(self, points: np.ndarray) -> np.ndarray:
        """(n, K) the segments listed for each point's cell (the padding index m where the
        list is shorter; points outside the grid use its nearest border cell)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        col = np.floor((np.nan_to_num(points[:, 0]) - self.origin[0]) / self.cell)
        row = np.floor((np.nan_to_num(points[:, 1]) - self.origin[1]) / self.cell)
        col = np.clip(col, 0, self.shape[0] - 1).astype(np.int64)
        row = np.clip(row, 0, self.shape[1] - 1).astype(np.int64)
        return self.near_table[row * self.shape[0] + col]

    def closest(self, points: np.ndarray, candidates: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For each point (n, 2) and its candidate segments (n, K): the vector from the
        nearest point of each candidate to the point (n, K, 2), its length (n, K) and the
        position t ∈ [0, 1] along the candidate (n, K)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        a, b = self.start[candidates], self.end[candidates]
        vec = b - a
        rel = points[:, None, :] - a
        length2 = np.maximum(np.einsum("nkc,nkc->nk", vec, vec), 1e-300)
        t = np.minimum(np.maximum(np.einsum("nkc,nkc->nk", rel, vec) / length2, 0.0), 1.0)
        away = rel - t[..., None] * vec
        return away, np.hypot(away[..., 0], away[..., 1]), t

