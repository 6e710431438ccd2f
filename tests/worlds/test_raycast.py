"""`World.first_hit` against an independent shapely computation, for points and disks."""

import numpy as np
import pytest
from shapely.geometry import LineString, Point

from bounce_gym.worlds import World

L_SHAPE = [(0, 0), (600, 0), (600, 230), (260, 230), (260, 460), (0, 460)]
ROOM_WITH_HOLES = World(
    [(0, 0), (20, 0), (20, 12), (11, 12), (11, 16), (0, 16)],
    [[(3, 3), (6, 3), (5, 7)], [(12, 2), (16, 2), (16, 5), (12, 5)]],
)


def _shapely_point_hit(world, origin, direction):
    far = LineString([origin, origin + direction * 10 * world.diameter])
    inter = far.intersection(world.polygon.boundary)
    pts = [inter] if inter.geom_type == "Point" else list(getattr(inter, "geoms", []))
    dists = [Point(origin).distance(p) for p in pts if Point(origin).distance(p) > 1e-9]
    return min(dists)


@pytest.mark.parametrize("world", [World(L_SHAPE), ROOM_WITH_HOLES])
def test_point_rays_match_shapely(world):
    rng = np.random.default_rng(0)
    origins = world.sample_free(rng, 300)
    angles = rng.uniform(0, 2 * np.pi, 300)
    dirs = np.column_stack((np.cos(angles), np.sin(angles)))
    hits = world.first_hit(origins, dirs)
    expected = [_shapely_point_hit(world, o, d) for o, d in zip(origins, dirs, strict=True)]
    np.testing.assert_allclose(hits.distance, expected, rtol=1e-9, atol=1e-9)
    # the contact lies on the reported edge and the normal is that edge's inward normal
    contact = origins + dirs * hits.distance[:, None]
    a, b = world.edge_start[hits.edge], world.edge_end[hits.edge]
    cross = (b - a)[:, 0] * (contact - a)[:, 1] - (b - a)[:, 1] * (contact - a)[:, 0]
    np.testing.assert_allclose(cross / world.lengths[hits.edge], 0, atol=1e-7)
    np.testing.assert_array_equal(hits.normal, world.normals[hits.edge])
    assert (np.einsum("ij,ij->i", dirs, hits.normal) < 0).all()
    assert (hits.vertex == -1).all()


@pytest.mark.parametrize("radius", [0.25, 1.0])
def test_swept_disk_stops_exactly_at_first_touch(radius):
    world = ROOM_WITH_HOLES
    rng = np.random.default_rng(1)
    origins = world.sample_free(rng, 300, radius=radius)
    angles = rng.uniform(0, 2 * np.pi, 300)
    dirs = np.column_stack((np.cos(angles), np.sin(angles)))
    hits = world.first_hit(origins, dirs, radius=radius)
    contact = origins + dirs * hits.distance[:, None]
    # at the contact the disk touches the boundary; a little before, it is clear of it
    np.testing.assert_allclose(world.boundary_distance(contact), radius, atol=1e-9)
    before = origins + dirs * np.maximum(hits.distance - 1e-6, 0)[:, None]
    assert (world.boundary_distance(before) > radius - 1e-12).all()
    # the swept segment stays clear of the walls (coarse independent check with shapely)
    for o, c in zip(origins[:50], contact[:50], strict=True):
        path = LineString([o, c]).buffer(radius * (1 - 1e-6))
        assert world.polygon.contains(path)
    # vertex contacts report the direction from the vertex to the centre
    at_vertex = hits.vertex >= 0
    assert at_vertex.any()
    rel = contact[at_vertex] - world.edge_start[hits.vertex[at_vertex]]
    np.testing.assert_allclose(rel / radius, hits.normal[at_vertex], atol=1e-9)


def test_resting_on_a_wall_blocks_only_when_facing_it():
    w = World([(0, 0), (10, 0), (10, 8), (0, 8)])
    on_wall = np.array([[10.0, 4.0], [10.0, 4.0], [10.0 + 1e-12, 4.0]])
    dirs = np.array([[1.0, 0.0], [-1.0, 0.0], [np.cos(3.1415), np.sin(3.1415)]])
    hits = w.first_hit(on_wall, dirs)
    assert hits.distance[0] == 0.0
    assert hits.distance[1] == pytest.approx(10.0)
    assert hits.distance[2] == pytest.approx(10.0, rel=1e-6)


def test_grazing_ray_from_just_outside_the_wall_line_still_hits_it():
    """Regression: a robot rounded 1e-11 behind the wall and heading almost along it."""
    w = World([(0, 0), (10, 0), (10, 8), (0, 8)])
    heading = np.pi - 3e-4  # almost along the top wall, slightly into it
    hit = w.first_hit(np.array([[5.0, 8.0 + 1e-11]]), np.array([[np.cos(heading), np.sin(heading)]]))
    assert hit.distance[0] == 0.0 and hit.edge[0] == 2


def test_large_batches_are_chunked_consistently():
    rng = np.random.default_rng(2)
    world = ROOM_WITH_HOLES
    origins = world.sample_free(rng, 5000)
    angles = rng.uniform(0, 2 * np.pi, 5000)
    dirs = np.column_stack((np.cos(angles), np.sin(angles)))
    full = world.first_hit(origins, dirs, 0.2)
    one_by_one = [world.first_hit(origins[i : i + 1], dirs[i : i + 1], 0.2) for i in range(0, 5000, 97)]
    np.testing.assert_array_equal(full.distance[::97], [h.distance[0] for h in one_by_one])
    np.testing.assert_array_equal(full.edge[::97], [h.edge[0] for h in one_by_one])


@pytest.mark.parametrize("radius", [0.0, 0.4])
def test_single_ray_path_matches_the_batched_path(radius):
    rng = np.random.default_rng(4)
    world = ROOM_WITH_HOLES
    origins = world.sample_free(rng, 400, radius=radius)
    angles = rng.uniform(0, 2 * np.pi, 400)
    dirs = np.column_stack((np.cos(angles), np.sin(angles)))
    batch = world.first_hit(origins, dirs, radius)
    for i in range(400):
        one = world.first_hit(origins[i], dirs[i], radius)
        assert one.edge[0] == batch.edge[i] and one.vertex[0] == batch.vertex[i]
        assert one.distance[0] == pytest.approx(batch.distance[i], rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(one.normal[0], batch.normal[i], atol=1e-12)


@pytest.mark.parametrize("radius", [0.15, 0.4])  # a point (radius 0) tests no vertex
def test_reflex_vertices_in_a_loop_or_in_numpy_give_the_same_bits(radius, monkeypatch):
    """A world with few reflex vertices tests them in a Python loop, a large one with numpy:
    both give every single-ray cast bit for bit alike, skipped edges included."""
    from bounce_gym.worlds import raycast

    world = ROOM_WITH_HOLES
    rng = np.random.default_rng(9)
    origins = world.sample_free(rng, 300, radius=radius)
    angles = rng.uniform(0, 2 * np.pi, 300)
    skips = [frozenset(), frozenset({1}), frozenset({0, 7})]
    rays = [(*origins[i].tolist(), np.cos(angles[i]), np.sin(angles[i]), skips[i % 3])
            for i in range(300)]
    assert 0 < len(raycast.features(world, radius).vx) <= raycast.LOOP_VERTICES
    looped = [raycast.first_hit_scalar(world, *ray[:4], radius, ray[4]) for ray in rays]
    monkeypatch.setattr(raycast, "LOOP_VERTICES", -1)
    assert [raycast.first_hit_scalar(world, *ray[:4], radius, ray[4]) for ray in rays] == looped
