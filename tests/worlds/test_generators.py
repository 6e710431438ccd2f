"""Seeded random worlds (bounce_gym.worlds.generators)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from bounce_gym.errors import ConfigError
from bounce_gym.worlds import (
    World,
    random_grid,
    random_room_tree,
    random_star_polygon,
    world_from_grid,
)

SEEDS = range(8)


def rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(seed)


# -- star polygons ----------------------------------------------------------------------------
def test_star_same_seed_same_world():
    a = random_star_polygon(rng(3))
    b = random_star_polygon(rng(3))
    assert a == b
    assert a is not b


def test_star_different_seeds_differ():
    worlds = [random_star_polygon(rng(s)) for s in SEEDS]
    assert len(set(worlds)) == len(worlds)


@pytest.mark.parametrize("n", [3, 7, 20, 45])
def test_star_vertex_count_and_bounds(n):
    for seed in SEEDS:
        world = random_star_polygon(rng(seed), n_vertices=n, center=(5, -3), avg_radius=2)
        assert isinstance(world, World)
        assert len(world.outer) == n
        assert not world.holes
        radii = np.hypot(world.outer[:, 0] - 5, world.outer[:, 1] + 3)
        assert np.all(radii <= 4 + 1e-12)  # clipped to [0, 2 * avg_radius]


def test_star_vertices_increase_in_angle():
    # Star-shaped around the centre: the polar angles of the vertices go round once.
    world = random_star_polygon(rng(0), irregularity=0.1, spikiness=0.2)
    angles = np.arctan2(world.outer[:, 1] - 250, world.outer[:, 0] - 250)
    steps = np.mod(np.diff(np.append(angles, angles[0])), 2 * np.pi)
    assert np.isclose(steps.sum(), 2 * np.pi)


def test_star_zero_noise_is_regular():
    world = random_star_polygon(rng(1), n_vertices=6, irregularity=0.0, spikiness=0.0)
    radii = np.hypot(*(world.outer - 250).T)
    assert np.allclose(radii, 100)
    assert np.allclose(world.lengths, world.lengths[0])


def test_star_high_irregularity_is_rejected_and_redrawn():
    # The published grid's corner (irr = 0.4 > 2*pi/20, spikiness 0.5) self-intersects often
    # (Nilles et al. 2021, section 7.3); every returned polygon must still be a valid World.
    for seed in range(20):
        world = random_star_polygon(rng(seed), irregularity=0.4, spikiness=0.5)
        assert len(world.outer) == 20


def test_star_gives_up_with_clear_error():
    with pytest.raises(ConfigError, match="max_attempts=3.*irregularity"):
        random_star_polygon(rng(0), irregularity=50.0, spikiness=0.5, max_attempts=3)


def test_generators_do_not_touch_global_rng():
    np.random.seed(123)
    state = np.random.get_state()[1].copy()
    random_star_polygon(rng(0))
    random_room_tree(rng(0))
    random_grid(rng(0), 8, 8, 3, 2)
    assert np.array_equal(np.random.get_state()[1], state)


# -- room trees -------------------------------------------------------------------------------
def test_room_tree_same_seed_same_world():
    assert random_room_tree(rng(5), n_rooms=6) == random_room_tree(rng(5), n_rooms=6)


def test_room_tree_different_seeds_differ():
    worlds = [random_room_tree(rng(s)) for s in SEEDS]
    assert len(set(worlds)) == len(worlds)


@pytest.mark.parametrize("n_rooms", [1, 2, 4, 9])
def test_room_tree_structure(n_rooms):
    lo, hi, door, wall = 3.0, 6.0, 1.0, 0.4
    for seed in SEEDS:
        world = random_room_tree(
            rng(seed), n_rooms=n_rooms, room_size=(lo, hi), door_width=door, wall=wall
        )
        assert not world.holes  # one simple polygon
        # A rectangle, then 8 vertices per door (2 on each side of the wall + 4 room corners).
        assert len(world.outer) == 4 + 8 * (n_rooms - 1)
        # Axis-aligned: every edge horizontal or vertical.
        assert np.all(np.isclose(world.tangents, 0, atol=1e-12).any(axis=1))
        doors_area = (n_rooms - 1) * door * wall
        assert n_rooms * lo**2 + doors_area - 1e-9 <= world.area
        assert world.area <= n_rooms * hi**2 + doors_area + 1e-9


def test_room_tree_first_room_at_origin():
    world = random_room_tree(rng(2), n_rooms=1, room_size=(4, 4))
    assert world.bounds == (0.0, 0.0, 4.0, 4.0)


# -- grids ------------------------------------------------------------------------------------
def test_grid_same_seed_same_world():
    a = random_grid(rng(9), 12, 20, 8, 3)
    assert a == random_grid(rng(9), 12, 20, 8, 3)


def test_grid_different_seeds_differ():
    worlds = [random_grid(rng(s), 10, 10, 5, 3) for s in SEEDS]
    assert len(set(worlds)) == len(worlds)


@pytest.mark.parametrize(("rows", "cols", "n_obstacles", "max_size"),
                         [(10, 10, 6, 3), (12, 20, 12, 4), (15, 15, 10, 2), (3, 9, 2, 1)])
def test_grid_is_connected_and_full_size(rows, cols, n_obstacles, max_size):
    for seed in SEEDS:
        world = random_grid(rng(seed), rows, cols, n_obstacles, max_size)
        free = world.occupancy(1.0)
        assert free.shape == (rows, cols)
        assert free.sum() < rows * cols  # obstacles were placed
        _, regions = ndimage.label(free)  # 4-connectivity
        assert regions == 1
        a, b, c, d = free[:-1, :-1], free[1:, 1:], free[:-1, 1:], free[1:, :-1]
        assert not np.any((a & b & ~c & ~d) | (c & d & ~a & ~b))  # no diagonal pinch
        assert world_from_grid(free) == world


def test_grid_without_obstacles_is_a_rectangle():
    world = random_grid(rng(0), 4, 7, 0, 1)
    assert world.bounds == (0.0, 0.0, 7.0, 4.0)
    assert len(world.outer) == 4


def test_grid_cell_size():
    world = random_grid(rng(0), 6, 6, 3, 2, cell_size=0.5)
    assert world.bounds == (0.0, 0.0, 3.0, 3.0)
    assert world.occupancy(0.5).shape == (6, 6)


def test_grid_gives_up_with_clear_error():
    with pytest.raises(ConfigError, match="n_obstacles=60"):
        random_grid(rng(0), 3, 3, 60, 2, max_attempts=20)


# -- argument checking ------------------------------------------------------------------------
BAD_ARGS = [
    (random_star_polygon, {"n_vertices": 2}, "n_vertices"),
    (random_star_polygon, {"n_vertices": 5.0}, "n_vertices"),
    (random_star_polygon, {"n_vertices": True}, "n_vertices"),
    (random_star_polygon, {"avg_radius": 0}, "avg_radius"),
    (random_star_polygon, {"avg_radius": float("nan")}, "avg_radius"),
    (random_star_polygon, {"irregularity": -0.1}, "irregularity"),
    (random_star_polygon, {"spikiness": float("inf")}, "spikiness"),
    (random_star_polygon, {"spikiness": "0.3"}, "spikiness"),
    (random_star_polygon, {"center": (1.0,)}, "center"),
    (random_star_polygon, {"center": "ab"}, "center"),
    (random_star_polygon, {"max_attempts": 0}, "max_attempts"),
    (random_room_tree, {"n_rooms": 0}, "n_rooms"),
    (random_room_tree, {"room_size": (6, 4)}, "room_size"),
    (random_room_tree, {"room_size": 5}, "room_size"),
    (random_room_tree, {"room_size": (1.5, 8)}, "room_size"),  # too small for a door of 1
    (random_room_tree, {"room_size": (-1, 8)}, "room_size"),
    (random_room_tree, {"door_width": 0}, "door_width"),
    (random_room_tree, {"wall": -0.5}, "wall"),
    (random_grid, {"rows": 0, "cols": 5, "n_obstacles": 1, "max_size": 1}, "rows"),
    (random_grid, {"rows": 5, "cols": 2.5, "n_obstacles": 1, "max_size": 1}, "cols"),
    (random_grid, {"rows": 5, "cols": 5, "n_obstacles": -1, "max_size": 1}, "n_obstacles"),
    (random_grid, {"rows": 5, "cols": 5, "n_obstacles": 1, "max_size": 0}, "max_size"),
    (random_grid, {"rows": 5, "cols": 8, "n_obstacles": 1, "max_size": 6}, "max_size"),
    (random_grid, {"rows": 5, "cols": 5, "n_obstacles": 1, "max_size": 2, "cell_size": 0},
     "cell_size"),
]


@pytest.mark.parametrize(("func", "kwargs", "field"), BAD_ARGS,
                         ids=[f"{f.__name__}-{k}" for f, k, _ in BAD_ARGS])
def test_bad_arguments(func, kwargs, field):
    with pytest.raises(ConfigError) as info:
        func(rng(0), **kwargs)
    assert field in str(info.value)


@pytest.mark.parametrize("bad_rng", [0, None, np.random.RandomState(0)])
def test_rng_must_be_a_generator(bad_rng):
    with pytest.raises(ConfigError, match="rng"):
        random_star_polygon(bad_rng)
    with pytest.raises(ConfigError, match="rng"):
        random_room_tree(bad_rng)
    with pytest.raises(ConfigError, match="rng"):
        random_grid(bad_rng, 5, 5, 1, 1)
