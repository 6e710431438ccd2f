"""`GridGeodesic`: shortest paths through free cells along king moves, and the cell of a point."""

import math

import numpy as np
import pytest

from bounce_gym.cells.geodesic import GridGeodesic
from bounce_gym.errors import ConfigError

# rows bottom first: a wall across column 2 with a gap in the top row
WALL = np.array([[1, 1, 0, 1, 1],
                 [1, 1, 0, 1, 1],
                 [1, 1, 1, 1, 1]], dtype=bool)
R2 = math.sqrt(2)


def test_distances_go_around_obstacles_along_king_moves():
    g = GridGeodesic(WALL, 1.0, (0.0, 0.0))
    d = g.distances_to([0.5, 0.5])  # from the cell (0, 0)
    node = g.node_of
    assert d[node([0.5, 0.5])[0]] == 0.0
    assert d[node([1.5, 1.5])[0]] == pytest.approx(R2)
    # (0, 0) -> (1, 1) -> (2, 2) -> (1, 3) -> (0, 4): around the wall's top end
    assert d[node([4.5, 0.5])[0]] == pytest.approx(4 * R2)
    assert d[node([2.5, 2.5])[0]] == pytest.approx(2 * R2)
    assert g.n_nodes == WALL.sum()


@pytest.mark.parametrize(("rule", "expected"), [("target_only", R2), ("no_squeeze", R2),
                                                ("strict", 2.0)])
def test_the_corner_rule_decides_which_diagonals_exist(rule, expected):
    """(0, 0) to (1, 1) with the side cell (0, 1) blocked: ``strict`` forbids the diagonal."""
    free = np.array([[1, 0], [1, 1]], dtype=bool)
    g = GridGeodesic(free, 1.0, (0.0, 0.0), rule)
    assert g.distances_to([0.5, 0.5])[g.node_of([1.5, 1.5])[0]] == pytest.approx(expected)


def test_points_map_to_their_cell_or_the_nearest_free_one():
    g = GridGeodesic(WALL, 2.0, (10.0, 20.0))
    assert g.node_of([[10.1, 20.1], [19.9, 25.9], [20.0, 26.0]]).tolist() == [0, 12, 12]
    # inside the wall's cell (0, 2): the nearest free cell centre is (0, 1) or (0, 3)
    assert g.node_of([15.0, 21.0])[0] in (1, 2)
    d = g.distances_to([11.0, 21.0])
    assert d[g.node_of([13.0, 23.0])[0]] == pytest.approx(2.0 * R2)  # scaled by the cell size


def test_disconnected_cells_are_infinitely_far():
    free = np.array([[1, 0, 1]], dtype=bool)
    g = GridGeodesic(free, 1.0, (0.0, 0.0))
    assert g.distances_to([0.5, 0.5]).tolist() == [0.0, math.inf]


def test_bad_grids_and_rules_raise_config_error():
    with pytest.raises(ConfigError, match="corner_rule"):
        GridGeodesic(WALL, 1.0, (0.0, 0.0), "diagonal")
    with pytest.raises(ConfigError, match="no free cell"):
        GridGeodesic(np.zeros((2, 2), dtype=bool), 1.0, (0.0, 0.0))


def test_node_at_is_node_of_for_one_point():
    g = GridGeodesic(WALL, 0.7, (-1.3, 2.9))
    points = np.random.default_rng(0).uniform([-2.0, 2.0], [3.0, 5.5], size=(500, 2))
    points[:3] = [[-1.3, 2.9], [-1.3 + 3.5, 2.9 + 2.1], [0.1, 3.6]]  # corners, a cell edge
    assert [g.node_at(x, y) for x, y in points] == g.node_of(points).tolist()
