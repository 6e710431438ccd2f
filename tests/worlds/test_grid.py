"""Grid maps (bounce_gym.worlds.grid): the same worlds as the cell-by-cell union, at numpy speed."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from bounce_gym.errors import InvalidWorldError
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


def _union_reference(free: np.ndarray, cell_size: float):
    """The former construction: the union of the free cells, its collinear vertices dropped,
    each ring started at its lowest, then leftmost vertex, the holes sorted by that vertex."""
    import shapely

    from bounce_gym.worlds import World

    rows, cols = np.nonzero(free)
    box = (cols.min(), rows.min(), cols.max() + 1, rows.max() + 1)
    if free.sum() == (box[2] - box[0]) * (box[3] - box[1]):
        union = shapely.box(*box)  # it unioned maximal rectangles: a lone one came back as given
    else:
        union = shapely.unary_union(shapely.box(cols, rows, cols + 1, rows + 1)).simplify(0)
    if union.geom_type != "Polygon":
        return f"{len(union.geoms)} separate regions"

    def canonical(coords):
        ring = np.asarray(coords)[:-1]
        return np.roll(ring, -np.lexsort((ring[:, 0], ring[:, 1]))[0], axis=0)

    holes = sorted((canonical(h.coords) for h in union.interiors), key=lambda h: (h[0, 1], h[0, 0]))
    return World(cell_size * canonical(union.exterior.coords), [cell_size * h for h in holes])


def test_traced_rings_are_the_union_of_the_free_cells_vertex_for_vertex():
    """The rings traced from the grid equal the former polygon union's exactly (same vertices,
    same order, same hole order), or fail with the same count of separate regions."""
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(150):
        rows, cols = (int(v) for v in rng.integers(1, 25, size=2))
        free = np.ones((rows, cols), dtype=bool)
        for _ in range(int(rng.integers(0, 25))):
            h, w, r, c = (int(v) for v in rng.integers(0, 4, size=4) + (1, 1, 0, 0))
            candidate = free.copy()
            top, left = r * rows // 4, c * cols // 4 + w
            candidate[top : top + h, left : left + w] = False
            a, b = candidate[:-1, :-1], candidate[1:, 1:]
            c_, d = candidate[:-1, 1:], candidate[1:, :-1]
            if candidate.any() and not np.any((a & b & ~c_ & ~d) | (c_ & d & ~a & ~b)):
                free = candidate
        reference = _union_reference(free, 0.5)
        if isinstance(reference, str):
            with pytest.raises(InvalidWorldError, match=reference):
                world_from_grid(free, 0.5)
            continue
        world = world_from_grid(free, 0.5)
        assert world == reference
        assert [h.tolist() for h in world.holes] == [h.tolist() for h in reference.holes]
        compared += 1
    assert compared > 100


@pytest.mark.timeout(120)  # a hang guard only: one test per pair of holes took hours here
def test_a_1200_by_1200_grid_map_with_160000_holes_loads():
    n = 1200
    free = np.ones((n, n), dtype=bool)
    free[1:-1:3, 1:-1:3] = False  # isolated blocked cells: 400 x 400 holes
    world = world_from_grid(free)
    holes = np.array(world.holes)
    assert holes.shape == (160_000, 4, 2) and world.area == free.sum()
    # unit squares at (1 + 3i, 1 + 3j), sorted bottom to top, then left to right
    low = holes.min(axis=1)
    assert np.array_equal(low[:, 1], np.repeat(1 + 3 * np.arange(400), 400))
    assert np.array_equal(low[:, 0], np.tile(1 + 3 * np.arange(400), 400))
    assert np.array_equal(holes.max(axis=1) - low, np.ones((160_000, 2)))
    assert world.outer.tolist() == [[n, 0], [n, n], [0, n], [0, 0]]
