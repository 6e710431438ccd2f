"""Where a drive of the cell model ends: every cell's drive to its next contact, tabulated.

A robot of the `CellModel` that is not blocked moves one king move per tick, keeping its bin,
until its target is blocked (`CellModel.targets`). That drive depends only on the cell it starts
from, so `ContactDrives` follows every cell's drive once and keeps, per cell number
``z = k · n_positions + p``, the cell where the drive stops and its ticks: a batch of robots then
drives to contact with a few array lookups instead of one numpy pass per tick.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.model import CellModel


class ContactDrives:
    """The drive to contact of every cell of ``model``.

    Attributes:
        next: (n_cells,) the cell one tick of driving leads to (itself where blocked).
        hop: (n_cells,) the length of that tick's move (0 where blocked), as
            ``np.hypot`` of the difference of the two cell centres.
        end: (n_cells,) the cell where the drive stops (blocked).
        ticks: (n_cells,) the drive's ticks (its moves).
    """

    def __init__(self, model: CellModel) -> None:
        n_pos = model.n_positions
        z = np.arange(model.n_cells, dtype=np.int64)
        p, k = model.decode(z)
        target = model.targets[k, p]
        moves = target >= 0
        self.next = np.where(moves, k * n_pos + target, z)
        gap = model.centres[np.where(moves, target, p)] - model.centres[p]
        self.hop = np.where(moves, np.hypot(gap[:, 0], gap[:, 1]), 0.0)
        self.end = z.copy()
        self.ticks = np.zeros(model.n_cells, dtype=np.int64)
        going = np.flatnonzero(moves)
        while len(going):  # a drive is a straight line, so this ends within the grid's size
            self.end[going] = self.next[self.end[going]]
            self.ticks[going] += 1
            going = going[self.next[self.end[going]] != self.end[going]]

    def add_hops(self, cells: np.ndarray, odometer: np.ndarray) -> np.ndarray:
        """``odometer`` (one entry per cell of ``cells``) plus the moves of each cell's drive,
        added one tick at a time as a robot stepping tick by tick adds them (so bit for bit
        the same sums)."""
        odometer = odometer.copy()
        for _ in range(int(self.ticks[cells].max(initial=0))):
            odometer += self.hop[cells]  # + 0.0 once a drive has stopped: no change
            cells = self.next[cells]
        return odometer
