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


#: faults of one hole of `_many_holes` (unit squares at (3i + 1, 3j + 1) in a 60 x 60
#: square), by the message they give
HOLE_FAULTS = {
    "zero-length edge": lambda x, y: [(x, y), (x + 1, y), (x + 1, y), (x, y + 1)],
    "is repeated": lambda x, y: [(x, y), (x + 1, y), (x + 0.5, y + 0.5), (x + 1, y + 1),
                                 (x, y + 1), (x + 0.5, y + 0.5)],
    "collinear-degenerate": lambda x, y: [(x, y), (x + 1, y), (x + 0.5, y), (x + 0.5, y + 1)],
    "self-intersects": lambda x, y: [(x, y), (x + 1, y + 1), (x + 1, y), (x, y + 1)],
    "not finite": lambda x, y: [(x, y), (x + 1, y), (x, np.inf)],
    "at least 3 vertices": lambda x, y: [(x, y), (x + 1, y)],
    r"shape \(n, 2\)": lambda x, y: [(x, y, 0), (x + 1, y, 0), (x, y + 1, 0)],
}
BIG = [(0, 0), (60, 0), (60, 60), (0, 60)]


def _many_holes(faults: dict[int, str] | None = None) -> list:
    holes = [[(3 * i + 1, 3 * j + 1), (3 * i + 2, 3 * j + 1), (3 * i + 2, 3 * j + 2),
              (3 * i + 1, 3 * j + 2)] for j in range(20) for i in range(20)]
    for k, fault in (faults or {}).items():
        holes[k] = HOLE_FAULTS[fault](*holes[k][0])
    return holes


@pytest.mark.parametrize("first", HOLE_FAULTS)
@pytest.mark.parametrize("later", ["zero-length edge", "not finite", "self-intersects",
                                   "at least 3 vertices"])
def test_the_first_faulty_hole_of_many_is_the_one_reported(first, later):
    """All holes are checked at once, with the message and the hole that checking them one by
    one gave: the lowest-numbered faulty hole, whatever the faults of later holes."""
    with pytest.raises(InvalidWorldError, match=rf"^hole 37: .*{first}"):
        World(BIG, _many_holes({37: first, 38: later, 390: later}))


def test_placement_faults_of_holes_come_after_every_holes_own_faults():
    outside = _many_holes({38: "self-intersects"})
    outside[5] = [(70, 70), (71, 70), (71, 71)]
    with pytest.raises(InvalidWorldError, match="^hole 38: ring self-intersects"):
        World(BIG, outside)
    outside[38] = _many_holes()[38]
    outside[4] = [(0, 4), (1, 4), (1, 5)]
    with pytest.raises(InvalidWorldError, match="^hole 4: touches the outer ring"):
        World(BIG, outside)


def test_the_first_pair_of_meeting_holes_is_the_one_reported():
    holes = _many_holes()
    holes[41] = [(x + 1, y) for x, y in holes[40]]  # shares an edge with hole 40
    holes[8] = [(x + 0.5, y) for x, y in holes[7]]  # overlaps hole 7
    with pytest.raises(InvalidWorldError, match="^holes 7 and 8 overlap; holes must be disjoint"):
        World(BIG, holes)
    holes[8] = _many_holes()[8]
    with pytest.raises(InvalidWorldError, match="^holes 40 and 41 touch"):
        World(BIG, holes)


def test_many_valid_holes_are_stored_clockwise_with_their_edges():
    holes = _many_holes()
    holes[::2] = [h[::-1] for h in holes[::2]]  # half of them clockwise already
    world = World(BIG, holes)
    assert len(world.holes) == 400 and world.area == 3600 - 400
    for hole, given in zip(world.holes, holes, strict=True):
        hx, hy = hole[:, 0], hole[:, 1]
        assert np.dot(hx, np.roll(hy, -1)) - np.dot(np.roll(hx, -1), hy) < 0  # clockwise
        assert sorted(map(tuple, hole.tolist())) == sorted(map(tuple, given))
    assert world.reflex.sum() == 4 * 400 and world.n_edges == 4 + 4 * 400


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


@pytest.mark.parametrize("seed", range(3))
def test_occupancy_of_a_disk_robot_needs_no_point_edge_pairs_and_gives_the_same_grid(seed):
    """With many edges `World.occupancy` finds the edges near each cell centre with an R-tree
    instead of measuring every centre against every edge: the same grid as the all-pairs
    `boundary_distance` test, exact ties (radius 0.5 or 1 from a grid wall) included."""
    from bounce_gym.worlds.generators import random_grid
    from bounce_gym.worlds.world import _INDEXED_EDGES

    w = random_grid(np.random.default_rng(seed), 40, 30, 25, 4)
    assert w.n_edges > _INDEXED_EDGES  # the R-tree path
    for cell in (1.0, 0.5, 0.7):
        inside = w.occupancy(cell)
        rows, cols = inside.shape
        xmin, ymin = w.bounds[:2]
        gx, gy = np.meshgrid(xmin + (np.arange(cols) + 0.5) * cell,
                             ymin + (np.arange(rows) + 0.5) * cell)
        distance = w.boundary_distance(np.column_stack((gx.ravel(), gy.ravel())))
        for radius in (0.3, 0.5, 1.0, 1.5, 2.25):
            expected = inside & (distance >= radius).reshape(rows, cols)
            assert np.array_equal(w.occupancy(cell, radius), expected), (cell, radius)


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
