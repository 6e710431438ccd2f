"""World construction, validation errors, immutability and derived geometry."""

import pickle

import numpy as np
import pytest

from bounce_gym.errors import InvalidWorldError
from bounce_gym.worlds import World, world_from_grid

SQUARE = [(0, 0), (10, 0), (10, 10), (0, 10)]
HOLE = [(2, 2), (4, 2), (4, 4), (2, 4)]


def test_orientation_is_normalised_outer_ccw_holes_cw():
    w = World(SQUARE[::-1], [HOLE])  # clockwise outer, counter-clockwise hole
    x, y = w.outer[:, 0], w.outer[:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0
    hx, hy = w.holes[0][:, 0], w.holes[0][:, 1]
    assert np.dot(hx, np.roll(hy, -1)) - np.dot(np.roll(hx, -1), hy) < 0


def test_inward_normals_point_into_free_space():
    w = World(SQUARE, [HOLE])
    mid = (w.edge_start + w.edge_end) / 2
    assert w.contains(mid + 1e-3 * w.normals).all()
    assert not w.contains(mid - 1e-3 * w.normals).any()


def test_reflex_vertices_are_the_hole_corners_and_the_l_notch():
    w = World(SQUARE, [HOLE])
    assert w.reflex.tolist() == [False] * 4 + [True] * 4
    ell = World([(0, 0), (600, 0), (600, 230), (260, 230), (260, 460), (0, 460)])
    assert np.flatnonzero(ell.reflex).tolist() == [3]


def test_closing_vertex_is_accepted():
    assert World([*SQUARE, SQUARE[0]]) == World(SQUARE)


@pytest.mark.parametrize(
    ("outer", "holes", "message"),
    [
        ([(0, 0), (1, 0)], [], "at least 3 vertices"),
        ([(0, 0), (1, 0), (np.nan, 1)], [], "not finite"),
        ([(0, 0), (1, 0), (np.inf, 1)], [], "not finite"),
        ([(0, 0), (1, 0), (1, 0), (0, 1)], [], "zero-length edge"),
        ([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2), (1, 1)], [], "repeated"),
        ([(0, 0), (2, 0), (1, 0), (1, 2)], [], "collinear-degenerate"),
        ([(0, 0), (1, 0), (2, 0)], [], "zero area|collinear"),
        ([(0, 0), (2, 2), (2, 0), (0, 2)], [], "self-intersects"),
        (SQUARE, [[(8, 8), (12, 8), (12, 9), (8, 9)]], "hole 0: not inside"),
        (SQUARE, [[(20, 20), (21, 20), (21, 21)]], "hole 0: not inside"),
        (SQUARE, [[(0, 2), (3, 2), (3, 3)]], "hole 0: touches the outer ring"),
        (SQUARE, [HOLE, [(3, 3), (5, 3), (5, 5), (3, 5)]], "holes 0 and 1 overlap"),
        (SQUARE, [HOLE, [(4, 4), (6, 4), (6, 6), (4, 6)]], "holes 0 and 1 touch"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [], r"shape \(n, 2\)"),
        ("abc", [], "sequence of"),
    ],
)
def test_invalid_worlds_raise_with_a_named_problem(outer, holes, message):
    with pytest.raises(InvalidWorldError, match=message):
        World(outer, holes)


def test_world_is_immutable_and_pickles_by_value():
    w = World(SQUARE, [HOLE], name="box")
    with pytest.raises(AttributeError):
        w.name = "other"
    with pytest.raises(ValueError):
        w.outer[0, 0] = 5.0
    w2 = pickle.loads(pickle.dumps(w))
    assert w2 == w and hash(w2) == hash(w) and w2.name == "box"


def test_contains_respects_radius_and_boundary():
    w = World(SQUARE, [HOLE])
    pts = np.array([[1, 1], [3, 3], [0, 5], [0.2, 5], [9.5, 9.5], [11, 5]])
    assert w.contains(pts).tolist() == [True, False, True, True, True, False]
    assert w.contains(pts, radius=0.5).tolist() == [True, False, False, False, True, False]


def test_occupancy_counts_free_cell_centres():
    w = World(SQUARE, [HOLE])
    occ = w.occupancy(1.0)
    assert occ.shape == (10, 10) and occ.sum() == 96
    assert not occ[2:4, 2:4].any()
    # radius 0.6: the outer ring of cells (centres 0.5 from the wall) is lost, and so are the 12
    # cells whose centres lie within 0.6 of the hole (the 4 diagonal ones are 0.707 away)
    assert w.occupancy(1.0, radius=0.6).sum() == 8 * 8 - 12


def test_world_from_grid_round_trips_through_occupancy():
    rng = np.random.default_rng(3)
    free = np.ones((6, 9), dtype=bool)
    free[2:4, 3:5] = False
    free[0, 8] = False
    w = world_from_grid(free)
    assert np.array_equal(w.occupancy(1.0), free)
    assert w.area == pytest.approx(free.sum())
    pts = w.sample_free(rng, 200)
    assert w.contains(pts).all()


def test_world_from_grid_rejects_pinches_and_disconnected_free_space():
    pinch = np.array([[True, False], [False, True]])
    with pytest.raises(InvalidWorldError, match="diagonal pinch"):
        world_from_grid(pinch)
    split = np.array([[True, False, True]])
    with pytest.raises(InvalidWorldError, match="separate regions"):
        world_from_grid(split)
    with pytest.raises(InvalidWorldError, match="no free cell"):
        world_from_grid(np.zeros((2, 2), dtype=bool))
    with pytest.raises(InvalidWorldError, match="cell_size"):
        world_from_grid(np.ones((2, 2), dtype=bool), cell_size=0)


def test_eroded_world_is_the_disk_c_space():
    w = World(SQUARE, [HOLE])
    c_space = w.eroded(0.5)
    assert c_space.area == pytest.approx(9 * 9 - (3 * 3 - (4 - np.pi) * 0.25), rel=1e-3)
    with pytest.raises(InvalidWorldError, match="radius"):
        w.eroded(-1)
