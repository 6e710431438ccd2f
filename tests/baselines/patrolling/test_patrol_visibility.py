"""Limited-range cell visibility and the Alg. 4.3 covers (Alam 2018, thesis ch. 4, §4.3.3)."""

import math

import numpy as np
import pytest

from baselines.patrolling.visibility import cell_visibility, complete_visibility, watch_region
from bounce_gym.errors import ConfigError


def _offsets(vis, row, col):
    z = int(np.flatnonzero((vis.cells == (row, col)).all(axis=1))[0])
    return {(int(r) - row, int(c) - col) for r, c in vis.cells[vis.visible_from(z)]}


def _walled():
    free = np.ones((15, 15), dtype=bool)
    free[3:12, 7] = False  # a vertical wall
    free[12, 2:5] = False
    return free


def test_open_grid_range_6_is_the_symmetric_disk_of_cells_inside_the_circle():
    vis = cell_visibility(np.ones((15, 15), dtype=bool), 6)
    seen = _offsets(vis, 7, 7)
    expected = {(dy, dx) for dy in range(-7, 8) for dx in range(-7, 8)
                if math.hypot(abs(dx) + 0.5, abs(dy) + 0.5) <= 6}
    assert seen == expected
    assert seen == {(dx, dy) for dy, dx in seen} == {(-dy, dx) for dy, dx in seen}
    assert (0, 5) in seen and (0, 6) not in seen and (4, 4) not in seen and (3, 4) in seen


def test_a_wall_blocks_the_cells_behind_it():
    free = _walled()
    vis = cell_visibility(free, 6)
    seen = _offsets(vis, 7, 5)  # two cells left of the wall
    assert (0, 1) in seen  # next to the wall
    assert not any(dx >= 2 for _, dx in seen)  # nothing on the far side of the wall
    open_seen = _offsets(cell_visibility(np.ones_like(free), 6), 7, 5)
    assert (0, 3) in open_seen and (0, 3) not in seen


def test_centre_line_of_sight_is_symmetric():
    vis = cell_visibility(_walled(), 6, rule="centre")
    dense = vis.seen.toarray()
    assert (dense == dense.T).all()
    assert 0 < dense.sum() < dense.size


def test_corner_rule_is_stricter_than_the_centre_rule():
    corners = cell_visibility(_walled(), 6).seen.toarray()
    centre = cell_visibility(_walled(), 6, rule="centre").seen.toarray()
    assert (corners <= centre).all() and corners.sum() < centre.sum()


@pytest.mark.parametrize("m", [1, 2, 3])
def test_every_robot_cover_sees_every_free_cell(m):
    vis = cell_visibility(_walled(), 6)
    covers = complete_visibility(vis, m)
    assert len(covers) == m
    for cover in covers:
        seen = np.zeros(len(vis), dtype=bool)
        for z in cover:
            seen[vis.visible_from(z)] = True
        assert seen.all()
        assert len(set(cover)) == len(cover)


def test_robot_i_takes_the_i_th_largest_new_coverage():
    vis = cell_visibility(_walled(), 6)
    seen = vis.seen.toarray().astype(int)
    for i, cover in enumerate(complete_visibility(vis, 3)):
        uncovered = np.ones(len(vis), dtype=int)
        for z in cover:
            gain = seen @ uncovered
            useful = [(-gain[k], k) for k in np.flatnonzero(gain > 0)]
            ranked = [k for _, k in sorted(useful)]
            assert z == ranked[min(i, len(ranked) - 1)]
            uncovered[seen[z] > 0] = 0


def test_covers_are_deterministic():
    a = complete_visibility(cell_visibility(_walled(), 6), 2)
    b = complete_visibility(cell_visibility(_walled(), 6), 2)
    assert a == b


@pytest.mark.parametrize("shape, sensing_range", [((15, 15), 6), ((20, 9), 3), ((12, 12), 2.5)])
def test_greedy_cover_on_an_open_grid_is_within_the_set_cover_bound(shape, sensing_range):
    vis = cell_visibility(np.ones(shape, dtype=bool), sensing_range)
    biggest = int(np.asarray(vis.seen.sum(axis=1)).max())
    bound = (1 + math.log(biggest)) * math.ceil(len(vis) / biggest)
    assert len(complete_visibility(vis, 1)[0]) <= bound


def test_watch_region_splits_the_cells_and_rings_the_visible_set():
    vis = cell_visibility(np.ones((15, 15), dtype=bool), 3)
    z = int(np.flatnonzero((vis.cells == (7, 7)).all(axis=1))[0])
    region = watch_region(vis, z)
    assert np.array_equal(np.sort(np.concatenate((region.inside, region.outside))),
                          np.arange(len(vis)))
    assert set(region.boundary) <= set(region.inside) and z not in set(region.boundary)
    # on an open grid the boundary is the outer ring of the disk: its cells' offsets
    ring = {(int(r) - 7, int(c) - 7) for r, c in vis.cells[region.boundary]}
    disk = {(int(r) - 7, int(c) - 7) for r, c in vis.cells[region.inside]}
    assert ring == {(dy, dx) for dy, dx in disk
                    if any((dy + a, dx + b) not in disk for a in (-1, 0, 1) for b in (-1, 0, 1))}
    with pytest.raises(ConfigError, match="z"):
        watch_region(vis, len(vis))


def test_bad_input_raises_config_error():
    with pytest.raises(ConfigError, match="l"):
        cell_visibility(np.ones((3, 3), dtype=bool), 0)
    with pytest.raises(ConfigError, match="rule"):
        cell_visibility(np.ones((3, 3), dtype=bool), 2, rule="disk")
    with pytest.raises(ConfigError, match="free"):
        cell_visibility(np.zeros((3, 3), dtype=bool), 2)
    with pytest.raises(ConfigError, match="free"):
        cell_visibility(np.full((3, 3), 2), 2)
    with pytest.raises(ConfigError, match="m"):
        complete_visibility(cell_visibility(np.ones((3, 3), dtype=bool), 2), 0)
    with pytest.raises(ConfigError, match="seen from no cell"):
        complete_visibility(cell_visibility(np.ones((3, 3), dtype=bool), 0.5), 1)
