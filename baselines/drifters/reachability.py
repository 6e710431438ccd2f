"""Alam 2018, thesis ch. 5, Algorithm 5.4 PERSISTENTREACHABILITY: the cells of all layers a
profiling drifter released at x_I on the surface can reach in the long run (Problem 3).

As printed, the drifter changes layer **only at x_I**: it may sink or rise along the water
column below x_I and then drift in that layer, so ℛ is the union over the layers of the cells
the layer's drift leads to from the projection of x_I (FINDREACHABLECELLS on the layer's
connectivity matrix, line 4). The column stops at the first land cell below x_I, since a drifter
cannot pass through it (`DrifterCells.legal`). The thesis runs Alg. 5.1 per layer (line 3) only
for its connectivity matrix; a breadth-first search on the drift graph gives the same rows
without the transitive closure.

``vertical_anywhere=True`` lets the drifter rise or sink at every cell: ℛ is then everything the
start leads to in the 3-D graph of all actions (drift, up and down edges), a superset.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from baselines.drifters.graph import reachable
from bounce_gym import validate
from bounce_gym.cells import DOWN, DrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["DrifterReachability", "persistent_reachability", "three_d_graph"]


@dataclass(frozen=True, eq=False)
class DrifterReachability:
    """The output of Alg. 5.4.

    Attributes:
        start: the release state x_I (a surface cell).
        column: (k,) int64, the states x_I^(l) of the water column below x_I, surface first.
        reached: (N,) bool over all model states, the reachable set ℛ.
        vertical_anywhere: whether vertical moves were allowed at every cell.
    """

    start: int
    column: np.ndarray
    reached: np.ndarray
    vertical_anywhere: bool

    def states(self) -> np.ndarray:
        """The states of ℛ, ascending."""
        return np.flatnonzero(self.reached)


def three_d_graph(model: DrifterCells):
    """(N, N) CSR: the sum of the drift, up and down matrices (i -> j iff some action moves
    i to j with positive probability)."""
    drift, up, down = model.action_matrices()
    return (drift + up + down).tocsr()


def persistent_reachability(model: DrifterCells, start: int,
                            vertical_anywhere: bool = False) -> DrifterReachability:
    """Alg. 5.4 PERSISTENTREACHABILITY(ℰ, ℱ, x_I) with x_I = ``start``, a state of layer 0.

    Raises:
        ConfigError: ``model`` is not a `DrifterCells`, or ``start`` is not a surface state.
    """
    if not isinstance(model, DrifterCells):
        raise ConfigError(f"model: expected a DrifterCells, got {type(model).__name__}")
    start = validate.integer("start", start, 0, int(model.offsets[1]) - 1)
    vertical_anywhere = validate.flag("vertical_anywhere", vertical_anywhere)
    column = [start]
    while model.vertical[column[-1], DOWN] >= 0:
        column.append(int(model.vertical[column[-1], DOWN]))
    column_ = np.asarray(column, dtype=np.int64)
    if vertical_anywhere:
        reached = reachable(three_d_graph(model), [start])
    else:  # the drift matrix is block-diagonal by layer: one search serves every layer
        reached = reachable(model.drift_matrix(), column_)
    column_.flags.writeable = False
    reached.flags.writeable = False
    return DrifterReachability(start=start, column=column_, reached=reached,
                        vertical_anywhere=vertical_anywhere)
