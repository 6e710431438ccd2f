"""The per-robot greedy covers of Alg. 4.3 COMPLETEVISIBILITY(F, l) (Alam 2018, thesis ch. 4,
§4.3.3).

The cell visibility itself (VISIBLECELLS, Eq. 4.1) and the watch regions of §4.3.5 live in
`bounce_gym.cells.visibility` (the patrol environment needs them too); they are re-exported here.
"""

from __future__ import annotations

import math

import numpy as np

from bounce_gym import validate
from bounce_gym.cells.visibility import (
    RULES,
    CellVisibility,
    WatchRegion,
    cell_visibility,
    watch_region,
)
from bounce_gym.errors import ConfigError

__all__ = ["RULES", "CellVisibility", "WatchRegion", "cell_visibility", "complete_visibility",
           "watch_region"]


def complete_visibility(visibility: CellVisibility, m: int) -> list[list[int]]:
    """Alg. 4.3 COMPLETEVISIBILITY (lines 4-12): one cover of all free cells per robot.

    Robot i (1-based) repeatedly takes the viewing cell whose set covers the i-th largest number
    of cells not yet covered, ranking the sets that still cover something by (most newly covered
    cells, then lowest cell index); when fewer than i sets remain it takes the last one, so the
    loop always ends. Robot 1's cover is Chvátal's (1979) greedy set cover.

    Returns:
        m lists of viewing-cell indices, each in the order chosen; the union of the cells seen
        from each list is every free cell.

    Raises:
        ConfigError: ``m`` is not an integer >= 1, or some free cell is seen from no cell (the
            range is too short for a cell to see itself).
    """
    if not isinstance(visibility, CellVisibility):
        raise ConfigError(f"visibility: expected a CellVisibility, got "
                          f"{type(visibility).__name__}")
    m = validate.integer("m", m, 1)
    seen = visibility.seen.astype(np.int64)
    n = len(visibility)
    blind = np.flatnonzero(np.asarray(seen.sum(axis=0)).ravel() == 0)
    if len(blind):
        r, c = visibility.cells[blind[0]]
        raise ConfigError(f"l: {len(blind)} free cells (e.g. row {r}, column {c}) are seen from "
                          f"no cell with l = {visibility.l}; use l >= {math.sqrt(0.5):.4f}")
    covers = []
    for i in range(m):
        uncovered = np.ones(n, dtype=np.int64)
        chosen: list[int] = []
        while uncovered.any():
            gain = seen @ uncovered
            useful = np.flatnonzero(gain > 0)
            ranked = useful[np.lexsort((useful, -gain[useful]))]
            z = int(ranked[min(i, len(ranked) - 1)])
            chosen.append(z)
            uncovered[visibility.visible_from(z)] = 0
        covers.append(chosen)
    return covers
