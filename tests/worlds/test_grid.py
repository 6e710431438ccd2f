"""Grid maps (bounce_gym.worlds.grid): the same worlds as the cell-by-cell union, at numpy speed."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from bounce_gym.worlds import io, zoo
from bounce_gym.worlds.generators import random_grid
from bounce_gym.worlds.grid import parse_ascii, to_ascii, world_from_grid

#: Rings recorded from the former cell-by-cell ``unary_union`` of every free cell, with the holes
#: sorted by their lowest, then leftmost vertex (the order `world_from_grid` now returns them in;
#: the union's own order was arbitrary).
GOLDEN = json.loads((Path(__file__).parent / "data" / "grid_golden.json").read_text())


def _digest(world) -> dict:
    h = hashlib.sha256()
    for ring in world.rings:
        h.update(np.ascontiguousarray(ring, dtype=np.float64).tobytes())
        h.update(b"|")
    return {"vertices": [len(r) for r in world.rings], "area": world.area,
            "sha256": h.hexdigest()}


@pytest.mark.parametrize("name", sorted(GOLDEN["zoo"]))
def test_zoo_grid_maps_match_the_cell_union(name):
    assert _digest(zoo.get(name)) == GOLDEN["zoo"][name]


@pytest.mark.parametrize("case", GOLDEN["random_grid"], ids=lambda c: str(c["args"]))
def test_generated_grid_maps_match_the_cell_union(case):
    seed, rows, cols, n_obstacles, max_size, cell_size = case["args"]
    world = random_grid(np.random.default_rng(seed), rows, cols, n_obstacles, max_size,
                        cell_size=cell_size)
    expected = {k: v for k, v in case.items() if k != "args"}
    assert _digest(world) == expected


def test_holes_come_sorted_by_their_lowest_then_leftmost_vertex():
    world = zoo.get("grid_20x12")
    keys = [min((y, x) for x, y in h.tolist()) for h in world.holes]
    assert keys == sorted(keys) and len(keys) == 6


def _large_grid(n: int) -> np.ndarray:
    free = np.ones((n, n), dtype=bool)
    free[0, ::2] = False  # a comb along the bottom: n/2 notches
    free[n // 4 : n // 2, n // 4 : n // 2] = False  # one square hole
    free[2 * n // 3, 10 : n - 10] = False  # one long thin hole
    return free


@pytest.mark.timeout(60)  # a hang guard only: the cell-by-cell union did not finish in 60 s
@pytest.mark.parametrize("suffix", [".json", ".yaml"])
def test_a_3000_by_3000_grid_map_loads(tmp_path, suffix):
    n = 3000
    free = _large_grid(n)
    path = tmp_path / f"big{suffix}"
    path.write_text(json.dumps({"name": "big", "grid": to_ascii(free)}))  # JSON is valid YAML
    world = io.load(path)
    assert world.area == free.sum()
    assert len(world.outer) == 4 + 4 * (n // 2) - 2  # n/2 notches of 4 vertices, 2 merge corners
    assert [len(h) for h in world.holes] == [4, 4]
    assert np.array_equal(world.occupancy(1.0), free)


def test_parse_ascii_and_to_ascii_are_inverse_on_a_large_grid():
    free = np.random.default_rng(0).random((400, 300)) < 0.5
    assert np.array_equal(parse_ascii(to_ascii(free)), free)
    assert world_from_grid(_large_grid(40)).area == _large_grid(40).sum()
