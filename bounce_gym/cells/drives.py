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
        # pointer doubling: after round j, end[z] is the cell 2^j ticks from z (a blocked cell
        # maps to itself) and ticks[z] the moves among them, so a drive of L ticks takes
        # log2(L) + 1 passes over the cells — not one per tick of the longest drive
        end = self.next.copy()
        ticks = moves.astype(np.int64)
        while True:  # a drive is a straight line, so this ends within the grid's size
            after = end[end]
            if np.array_equal(after, end):
                break
            ticks += ticks[end]
            end = after
        self.end = end
        self.ticks = ticks
