"""The patrol graph of a World (Alam 2018, thesis §4.3): one vertex per free square cell, edges
between 8-neighbours, Euclidean edge lengths between cell centres.

Vertices are numbered like the position cells of `bounce_gym.cells.CellModel`: row-major from the
bottom-left cell (y up). Each vertex carries ``pos`` (its cell centre) and ``cell`` ((row, col) in
the occupancy grid); each edge carries ``length``. The same numbering as
`bounce_gym.cells.visibility` gives the free cells of ``world.occupancy(cell_size)``.
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from bounce_gym.cells.model import CORNER_RULES, king_move_allowed
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

__all__ = ["DEFAULT_CORNER_RULE", "cell_graph"]

#: A diagonal edge needs both side cells free: a robot never cuts an obstacle's corner.
DEFAULT_CORNER_RULE = "strict"

# half of the king moves: every undirected edge is generated once
_HALF_MOVES = ((0, 1), (1, -1), (1, 0), (1, 1))


def cell_graph(world: World, cell_size: float = 1.0,
               corner_rule: str = DEFAULT_CORNER_RULE) -> nx.Graph:
    """The 8-neighbour graph of the free cells of ``world``.

    Args:
        world: the workspace; a cell is free iff its centre lies in the free space.
        cell_size: side of a square cell.
        corner_rule: which diagonal edges exist (`bounce_gym.cells.CORNER_RULES`): ``"strict"``
            (default, no corner cutting), ``"no_squeeze"`` or ``"target_only"``.

    Returns:
        an undirected graph on ``0..n-1`` with ``pos``, ``cell`` and edge ``length`` attributes.
    """
    if corner_rule not in CORNER_RULES:
        raise ConfigError(f"corner_rule: expected one of {CORNER_RULES}, got {corner_rule!r}")
    free = world.occupancy(cell_size)
    rc = np.argwhere(free)
    if len(rc) == 0:
        raise ConfigError(f"cell_size: world {world.name!r} has no free cell of size {cell_size}")
    index = np.full(free.shape, -1, dtype=np.int64)
    index[rc[:, 0], rc[:, 1]] = np.arange(len(rc))
    xmin, ymin = world.bounds[:2]
    centres = np.column_stack((xmin + (rc[:, 1] + 0.5) * cell_size,
                               ymin + (rc[:, 0] + 0.5) * cell_size))
    graph = nx.Graph(name=world.name, cell_size=float(cell_size), corner_rule=corner_rule)
    for v, ((row, col), (x, y)) in enumerate(zip(rc, centres, strict=True)):
        graph.add_node(v, pos=(float(x), float(y)), cell=(int(row), int(col)))
    for drow, dcol in _HALF_MOVES:
        ok = king_move_allowed(free, rc[:, 0], rc[:, 1], drow, dcol, corner_rule)
        src = np.flatnonzero(ok)
        dst = index[rc[src, 0] + drow, rc[src, 1] + dcol]
        length = float(np.hypot(drow, dcol) * cell_size)
        graph.add_edges_from((int(a), int(b), {"length": length}) for a, b in zip(src, dst,
                                                                                   strict=True))
    return graph
