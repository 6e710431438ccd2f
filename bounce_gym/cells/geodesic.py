"""Shortest-path (geodesic) distances through the free cells of an occupancy grid.

The graph has one node per free cell of the grid (numbered as `CellModel` numbers its position
cells: row-major from the bottom-left) and an edge between two free cells a king move apart
when `king_move_allowed` accepts the move under the corner rule — the moves a robot of the cell
model makes. An edge is as long as the move: one cell side orthogonally, √2 sides diagonally.
Distances are Dijkstra's (`scipy.sparse.csgraph.dijkstra`) over that graph.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.sparse import csgraph

from bounce_gym.cells.model import CORNER_RULES, king_move_allowed
from bounce_gym.errors import ConfigError

#: the four king moves that, with their reverses, join every pair of neighbouring cells
_HALF_KING = ((0, 1), (1, 0), (1, 1), (1, -1))


class GridGeodesic:
    """Geodesic distances between the free cells of ``free``, and the cell of any point.

    Args:
        free: (rows, cols) bool occupancy grid, row 0 at the bottom (`World.occupancy`).
        cell_size: side of a cell.
        origin: (x, y) of the grid's bottom-left corner.
        corner_rule: which diagonal moves are allowed (`bounce_gym.cells.model`).

    A point maps to the cell that contains it (points on or a hair outside the grid's border to
    the nearest border cell); when that cell is blocked — a point of the free space in a cell
    whose centre is not free — to the free cell whose centre is nearest to that cell's centre.
    """

    def __init__(self, free: np.ndarray, cell_size: float, origin: tuple[float, float],
                 corner_rule: str = "target_only") -> None:
        if corner_rule not in CORNER_RULES:
            raise ConfigError(f"corner_rule: expected one of {CORNER_RULES}, got {corner_rule!r}")
        free = np.asarray(free, dtype=bool)
        if not free.any():
            raise ConfigError("geodesic distances: the grid has no free cell")
        self.shape = free.shape
        self.cell_size = float(cell_size)
        self.origin = (float(origin[0]), float(origin[1]))
        rc = np.argwhere(free)
        self.n_nodes = len(rc)
        index = np.full(free.shape, -1, dtype=np.int64)
        index[rc[:, 0], rc[:, 1]] = np.arange(self.n_nodes)
        rows, cols, lengths = [], [], []
        for drow, dcol in _HALF_KING:
            ok = king_move_allowed(free, rc[:, 0], rc[:, 1], drow, dcol, corner_rule)
            rows.append(index[rc[ok, 0], rc[ok, 1]])
            cols.append(index[rc[ok, 0] + drow, rc[ok, 1] + dcol])
            lengths.append(np.full(int(ok.sum()), math.hypot(drow, dcol) * self.cell_size))
        row, col, length = (np.concatenate(x) for x in (rows, cols, lengths))
        self.graph = sp.csr_matrix((length, (row, col)), shape=(self.n_nodes, self.n_nodes))
        # every grid cell -> the node of the nearest free cell (itself when free)
        from scipy import ndimage  # here: ~0.2 s of import an env's construction does not need

        _, (near_r, near_c) = ndimage.distance_transform_edt(~free, return_indices=True)
        self._node_of_cell = index[near_r, near_c].ravel()

    def node_of(self, points: np.ndarray) -> np.ndarray:
        """(n,) node of each point (n, 2)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        rows, cols = self.shape
        col = np.floor((points[:, 0] - self.origin[0]) / self.cell_size)
        row = np.floor((points[:, 1] - self.origin[1]) / self.cell_size)
        col = np.clip(col, 0, cols - 1).astype(np.int64)
        row = np.clip(row, 0, rows - 1).astype(np.int64)
        return self._node_of_cell[row * cols + col]

    def node_at(self, x: float, y: float) -> int:
        """`node_of` one point (x, y), in Python floats: the same arithmetic, without numpy's
        per-call cost (a lone robot's hot path)."""
        rows, cols = self.shape
        col = min(max(math.floor((x - self.origin[0]) / self.cell_size), 0), cols - 1)
        row = min(max(math.floor((y - self.origin[1]) / self.cell_size), 0), rows - 1)
        return int(self._node_of_cell[row * cols + col])

    def distances_to(self, point: np.ndarray) -> np.ndarray:
        """(n_nodes,) geodesic distance from every node to the node of ``point`` (the graph is
        undirected); ``inf`` for nodes not connected to it."""
        return self.distances_to_node(int(self.node_of(point)[0]))

    def distances_to_node(self, node: int) -> np.ndarray:
        """`distances_to` the point(s) of node ``node``."""
        return csgraph.dijkstra(self.graph, directed=False, indices=node)
