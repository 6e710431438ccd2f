"""Regions of cells (goals, regions, starts) in every form, in metres and degrees."""

import numpy as np
import pytest

from bounce_gym.cells import DrifterCells
from bounce_gym.envs.drifters.regions import parse_region
from bounce_gym.errors import ConfigError
from bounce_gym.flows import METRES_PER_DEGREE, get_flow

BASIN = DrifterCells(get_flow("two_sink", n_layers=2))  # 1 km cells, land east of column 25
BIGHT = DrifterCells(get_flow("scb_like"), t=0.0)  # 0.02 degree cells


def cells(region, model=BASIN):
    return {tuple(c) for c in model.cells[region.states].tolist()}


def test_one_cell_and_a_list_of_cells():
    assert cells(parse_region((1, 3, 4), BASIN, "goal")) == {(1, 3, 4)}
    assert cells(parse_region(np.array([0, 3, 4]), BASIN, "goal")) == {(0, 3, 4)}
    region = parse_region({"cells": [(0, 1, 1), (1, 2, 2), (0, 1, 1)]}, BASIN, "goal")
    assert cells(region) == {(0, 1, 1), (1, 2, 2)} and region.point is None


def test_halo_is_a_chebyshev_block_of_water_cut_at_the_grid_and_land():
    assert len(parse_region({"cell": (0, 10, 10), "halo": 2}, BASIN, "goal").states) == 25
    assert cells(parse_region({"cell": (0, 0, 0), "halo": 1}, BASIN, "goal")) == {
        (0, 0, 0), (0, 0, 1), (0, 1, 0), (0, 1, 1)}
    near_land = cells(parse_region({"cell": (0, 5, 25), "halo": 1}, BASIN, "goal"))
    assert near_land == {(0, j, i) for j in (4, 5, 6) for i in (24, 25)}
    # the centre may be land as long as some of the block is water
    assert len(parse_region({"cell": (0, 5, 26), "halo": 1}, BASIN, "goal").states) == 3


def test_a_whole_layer():
    region = parse_region({"layer": 1}, BASIN, "region")
    assert np.array_equal(region.states, BASIN.layer_states(1))


def test_position_radius_in_metres_on_an_xy_grid():
    exact = parse_region({"position": (5200.0, 7100.0)}, BASIN, "start")
    assert cells(exact) == {(0, 7, 5)} and exact.point == (5200.0, 7100.0)
    disk = parse_region({"position": (5000.0, 7000.0), "radius": 1000.0, "layer": 1},
                        BASIN, "goal")
    assert cells(disk) == {(1, 7, 5), (1, 6, 5), (1, 8, 5), (1, 7, 4), (1, 7, 6)}
    assert disk.point is None
    both = parse_region({"position": (5000.0, 7000.0), "layer": "all"}, BASIN, "goal")
    assert cells(both) == {(0, 7, 5), (1, 7, 5)} and both.point is None


def test_position_radius_in_metres_on_a_lonlat_grid():
    lon, lat = BIGHT.field.x[5], BIGHT.field.y[5]
    dx = 0.02 * METRES_PER_DEGREE * np.cos(np.radians(lat))  # ~1853 m
    dy = 0.02 * METRES_PER_DEGREE  # 2222 m
    east_west = parse_region({"position": (lon, lat), "radius": dx + 1.0}, BIGHT, "goal")
    assert cells(east_west, BIGHT) == {(0, 5, 4), (0, 5, 5), (0, 5, 6)}
    plus = parse_region({"position": (lon, lat), "radius": dy + 1.0}, BIGHT, "goal")
    assert cells(plus, BIGHT) == {(0, 5, 4), (0, 5, 5), (0, 5, 6), (0, 4, 5), (0, 6, 5)}


@pytest.mark.parametrize(("spec", "message"), [
    ("surface", "^goal: expected a cell"),
    (3, "^goal: expected a cell"),
    ((0, 1), "^goal: expected a cell"),
    ((0, 1, 27), "^goal: cell .* is land"),
    ((2, 1, 1), r"^goal\[0\]"),
    ((0, 1.5, 1), r"^goal\[1\]"),
    ({"cell": (0, 1, 1), "radius": 2}, "^goal: expected a dict"),
    ({"halo": 1}, "^goal: expected a dict"),
    ({"cell": (0, 1, 1), "halo": -1}, r"^goal.halo"),
    ({"cell": (0, 20, 28), "halo": 0}, "^goal: no water cell"),
    ({"cells": []}, "^goal: 'cells' must be"),
    ({"cells": [(0, 1, 1), (0, 20, 28)]}, r"^goal.cells\[1\]: cell .* is land"),
    ({"position": (5.0, 5.0, 5.0)}, r"^goal.position: expected \(x, y\)"),
    ({"position": ("a", 5.0)}, r"^goal.position"),
    ({"position": (-2000.0, 5.0)}, r"^goal.position: .* outside the grid"),
    ({"position": (27000.0, 5000.0)}, "^goal: no water cell"),
    ({"position": (5.0, 5.0), "layer": 2}, r"^goal.layer"),
    ({"layer": -1}, r"^goal.layer"),
])
def test_bad_regions_name_the_argument(spec, message):
    with pytest.raises(ConfigError, match=message):
        parse_region(spec, BASIN, "goal")
