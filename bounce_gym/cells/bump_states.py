"""The decision state of a robot at a bump: the cell of `CellModel` that holds its pose.

A robot that bumps touches the boundary with its centre at ``position`` and faces it with its
``heading`` (the heading it drove with, before the rotation the bump starts). Its decision state
is the cell number ``z = k · N_pos + p`` of the cell model (`bounce_gym.cells.model`):

* ``p``: the position cell holding the contact point nudged `NUDGE` cell sides into the free
  space along the contact ``normal`` (so a robot touching a wall that runs along a grid line is
  in the cell on its own side of the line); a point on or a hair outside the grid's border
  counts in the nearest border cell, and a point in a cell whose centre is not free — a disk
  robot touches the boundary nearer than its radius to the centre of such a cell — in the free
  cell whose centre is nearest, as `bounce_gym.cells.geodesic.GridGeodesic` maps points;
* ``k``: the orientation bin nearest to ``heading`` (`CellModel.bin_of`).

On the cell backend the contact point is a cell centre and the heading a bin centre, so the
state is the robot's own cell.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.model import CellModel

#: How far (in cell sides) a contact point is moved into the free space before its cell is read.
NUDGE = 1e-6


class BumpStates:
    """Maps bump poses to the cell numbers of a `CellModel` (see the module docstring)."""

    def __init__(self, model: CellModel) -> None:
        self.model = model
        from scipy import ndimage  # here: ~0.2 s of import an env's construction does not need

        _, (near_r, near_c) = ndimage.distance_transform_edt(~model.free, return_indices=True)
        #: every grid cell (row-major) -> position index of the nearest free cell (itself if free)
        self.position_of_cell = model.position_index[near_r, near_c].ravel()

    def of(self, position: np.ndarray, heading: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """(n,) cell numbers of n bump poses: contact points (n, 2), headings (n,) in radians
        and unit contact normals (n, 2) pointing into the free space; -1 where a point is not
        finite (a robot that left the world)."""
        model = self.model
        point = (np.asarray(position, dtype=np.float64).reshape(-1, 2)
                 + NUDGE * model.cell_size * np.asarray(normal, dtype=np.float64).reshape(-1, 2))
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        ok = np.isfinite(point).all(axis=1) & np.isfinite(heading)
        out = np.full(len(point), -1, dtype=np.int64)
        if not ok.any():
            return out
        col = np.floor((point[ok, 0] - model.origin[0]) / model.cell_size)
        row = np.floor((point[ok, 1] - model.origin[1]) / model.cell_size)
        col = np.clip(col, 0, model.cols - 1).astype(np.int64)
        row = np.clip(row, 0, model.rows - 1).astype(np.int64)
        p = self.position_of_cell[row * model.cols + col]
        out[ok] = model.cell_id(p, model.bin_of(heading[ok]))
        return out
