"""The static board of the patrol environment: the cell graph of a World (Alam 2018, thesis
§4.3), its neighbours in the eight compass directions, and what the limited-range sensor of
Eq. 4.1 sees from every vertex.

Directions are numbered clockwise from north (y up): 0 N, 1 NE, 2 E, 3 SE, 4 S, 5 SW, 6 W,
7 NW — the order in which a robot without localisation tells its outgoing edges apart (§4.3).
The graph and the visibility number the free cells of ``world.occupancy(cell_size)`` alike
(row-major from the bottom-left cell); the visibility treats the blocked cells of that grid as
the obstacles and measures the range in cells.
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np

from bounce_gym.cells.patrol_graph import cell_graph
from bounce_gym.cells.visibility import CellVisibility, cell_visibility
from bounce_gym.worlds import World

#: Names of the patroller actions, clockwise from north.
DIRECTIONS = ("N", "NE", "E", "SE", "S", "SW", "W", "NW")
#: (row, column) offset of each direction; row grows northwards.
OFFSETS = ((1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1))


@dataclass(frozen=True, eq=False)
class PatrolBoard:
    """What every episode on one world shares.

    Attributes:
        world: the workspace.
        graph: the 8-neighbour cell graph (`bounce_gym.cells.patrol_graph.cell_graph`).
        visibility: the cells seen from each cell at the sensor range.
        neighbours: (n, 8) int64, the neighbour of vertex v in direction k, or -1 (read-only).
        seen: (n, n) bool, ``seen[z, c]`` iff a robot at z sees c; row z is also the watch
            region T of a target z (§4.3.5) (read-only).
    """

    world: World
    graph: nx.Graph
    visibility: CellVisibility
    neighbours: np.ndarray
    seen: np.ndarray

    @property
    def n(self) -> int:
        return self.graph.number_of_nodes()

    def uniform_walk(self) -> np.ndarray:
        """The uniform random walk on the graph, (n, n) row-stochastic; a vertex without edges
        keeps its walker (the only self-loop a strategy may have)."""
        moves = self.neighbours >= 0
        degree = moves.sum(axis=1)
        P = np.zeros((self.n, self.n))
        rows, dirs = np.nonzero(moves)
        P[rows, self.neighbours[rows, dirs]] = 1.0 / degree[rows]
        isolated = np.flatnonzero(degree == 0)
        P[isolated, isolated] = 1.0
        return P


def build_board(world: World, cell_size: float, corner_rule: str, sensor_range: float,
                visibility_rule: str) -> PatrolBoard:
    """The board of ``world`` (arguments already validated)."""
    graph = cell_graph(world, cell_size, corner_rule)
    visibility = cell_visibility(world.occupancy(cell_size), sensor_range, visibility_rule)
    cells = np.array([graph.nodes[v]["cell"] for v in range(graph.number_of_nodes())])
    index = {tuple(c): v for v, c in enumerate(cells.tolist())}
    neighbours = np.full((len(cells), len(OFFSETS)), -1, dtype=np.int64)
    for k, (drow, dcol) in enumerate(OFFSETS):
        for v, (row, col) in enumerate(cells.tolist()):
            u = index.get((row + drow, col + dcol))
            if u is not None and graph.has_edge(v, u):
                neighbours[v, k] = u
    seen = visibility.seen.toarray()
    neighbours.flags.writeable = False
    seen.flags.writeable = False
    return PatrolBoard(world=world, graph=graph, visibility=visibility, neighbours=neighbours,
                       seen=seen)
