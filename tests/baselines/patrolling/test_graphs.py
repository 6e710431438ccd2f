"""The 8-neighbour cell graph of a World (Alam 2018, thesis §4.3)."""

import math

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.graphs import cell_graph
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import zoo
from bounce_gym.worlds.grid import world_from_grid


def test_open_grid_has_king_edges_with_euclidean_lengths():
    graph = cell_graph(world_from_grid(np.ones((3, 4), dtype=bool)))
    assert graph.number_of_nodes() == 12
    # 3 rows x 3 horizontal + 2 x 4 vertical + 2 x 3 x 2 diagonals
    assert graph.number_of_edges() == 9 + 8 + 12
    lengths = sorted({d["length"] for *_, d in graph.edges(data=True)})
    assert lengths == pytest.approx([1.0, math.sqrt(2)])
    assert graph.nodes[0]["pos"] == (0.5, 0.5) and graph.nodes[0]["cell"] == (0, 0)
    assert graph.nodes[5]["cell"] == (1, 1)  # row-major from the bottom-left
    for u, v, d in graph.edges(data=True):
        gap = np.subtract(graph.nodes[u]["pos"], graph.nodes[v]["pos"])
        assert d["length"] == pytest.approx(float(np.hypot(*gap)))


def test_ring_around_a_blocked_cell_cuts_no_corner_by_default():
    free = np.ones((3, 3), dtype=bool)
    free[1, 1] = False
    world = world_from_grid(free)
    strict = cell_graph(world)
    assert strict.number_of_nodes() == 8
    assert strict.number_of_edges() == 8  # the four sides only
    assert nx.is_connected(strict)
    cutting = cell_graph(world, corner_rule="target_only")
    assert cutting.number_of_edges() == 12  # plus four diagonals past the blocked corner
    assert all(d["length"] == 1.0 for *_, d in strict.edges(data=True))


def test_cell_size_scales_positions_and_lengths():
    graph = cell_graph(world_from_grid(np.ones((2, 2), dtype=bool), cell_size=2.0), cell_size=2.0)
    assert graph.nodes[3]["pos"] == (3.0, 3.0)
    assert max(d["length"] for *_, d in graph.edges(data=True)) == pytest.approx(2 * math.sqrt(2))


def test_bad_corner_rule_is_named():
    with pytest.raises(ConfigError, match="corner_rule"):
        cell_graph(world_from_grid(np.ones((2, 2), dtype=bool)), corner_rule="cut")


def test_patrol_map_of_the_thesis_has_188_connected_cells():
    graph = cell_graph(zoo.get("patrol_15x15"))
    assert graph.number_of_nodes() == 188  # thesis §4.5.3: n = 188 free cells
    assert nx.is_connected(graph)
    assert graph.number_of_edges() <= 4 * 188  # at most 4 undirected king edges per cell
