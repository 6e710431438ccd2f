"""The base station and the angular partition of the centralised policies (Alam 2018, thesis
ch. 4, §4.3.4, Fig. 4.2): where b goes, which sector each cell falls in, and which of b's
comm-region cells stay as the overlap ring through which a robot reaches b's line of sight.

Cells are the free cells of a `CellVisibility`, given as their (row, col) with row 0 at the
bottom; geometry is in cell units with y up, on cell centres (x = col + 1/2, y = row + 1/2).
The rules where the thesis is open are in docs/choices/patrolling.md, "Stochastic patrolling: visibility
policies".
"""

from __future__ import annotations

import numpy as np

from baselines.patrolling.visibility import CellVisibility

__all__ = ["base_station", "kept_overlap", "sectors"]

# a cell on a sector's boundary ray belongs to the sector starting there, despite rounding
_ANGLE_TOL = 1e-9


def base_station(visibility_r: CellVisibility, centroid: np.ndarray) -> tuple[np.ndarray, int]:
    """The candidate cells and the base station b (thesis §4.3.4, both criteria of Fig. 4.2a).

    The candidates are the free cells whose centres lie within r/2 of ``centroid`` (when none
    does, the cells nearest to it). b is the candidate seeing the most cells within r (the
    communication range); ties go to the one nearer the centroid, then to the lower index.

    Returns:
        (candidates ascending, b).
    """
    centres = visibility_r.cells[:, ::-1] + 0.5
    distance = np.hypot(*(centres - centroid).T)
    candidates = np.flatnonzero(distance <= visibility_r.l / 2)
    if len(candidates) == 0:
        candidates = np.flatnonzero(distance == distance.min())
    seen = np.diff(visibility_r.seen.indptr)[candidates]
    best = candidates[np.lexsort((candidates, distance[candidates], -seen))[0]]
    return candidates, int(best)


def sectors(cells: np.ndarray, b: int, m: int) -> np.ndarray:
    """The sector of every cell around b: θ = atan2(Δy, Δx) from b's centre, in [0°, 360°),
    and sector ⌊θ / (360°/m)⌋, so that m = 3 gives [0°, 120°), [120°, 240°), [240°, 360°). b
    itself has θ = atan2(0, 0) = 0, sector 0."""
    dy, dx = (cells - cells[b]).T.astype(np.float64)
    theta = np.degrees(np.arctan2(dy, dx)) % 360.0
    return np.floor(theta / (360.0 / m) + _ANGLE_TOL).astype(np.int64) % m


def kept_overlap(cells: np.ndarray, sector: np.ndarray, comm: np.ndarray) -> np.ndarray:
    """Which cells are overlap cells: in the comm region ``comm`` and 8-adjacent to a free cell
    of the same sector outside it (bool per cell). The other comm cells are left to b."""
    n = len(cells)
    in_comm = np.zeros(n, dtype=bool)
    in_comm[comm] = True
    rows, cols = cells.T
    # sector + 1 of each free cell outside the comm region, 0 elsewhere; one cell of margin
    grid = np.zeros((rows.max() + 3, cols.max() + 3), dtype=np.int64)
    grid[rows[~in_comm] + 1, cols[~in_comm] + 1] = sector[~in_comm] + 1
    kept = np.zeros(n, dtype=bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                kept |= grid[rows + 1 + dr, cols + 1 + dc] == sector + 1
    return kept & in_comm
