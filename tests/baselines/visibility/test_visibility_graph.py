"""Partition P', BVG, safe intervals and G_safe (Nilles et al. 2021, §4, §5, §7)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines.visibility.graph import (
    bvg,
    reachability,
    safe_graph,
    safe_interval,
    visibility_matrix,
)
from baselines.visibility.partition import partition, visible_pairs
from bounce_gym import worlds
from bounce_gym.worlds import World
from bounce_gym.worlds.generators import random_star_polygon

PI = math.pi


def _adjacency(text: str) -> set[tuple[int, int]]:
    """Parse arc lists written as ``0→3,4; 1→2..5``."""
    arcs = set()
    for item in text.split(";"):
        src, dst = item.strip().split("→")
        for part in dst.split(","):
            if ".." in part:
                lo, hi = part.split("..")
                targets = range(int(lo), int(hi) + 1)
            else:
                targets = [int(part)]
            arcs |= {(int(src), t) for t in targets}
    return arcs


def _rotated_world(world: World, matrix: np.ndarray, shift=(0.0, 0.0)) -> World:
    return World(world.outer @ matrix.T + np.asarray(shift), [h @ matrix.T for h in world.holes])


# -- Prop. 2 safe intervals (§5) ------------------------------------------------------------------
@pytest.mark.parametrize(
    ("seg_i", "seg_j", "expected"),
    [
        (((0, 0), (1, 0)), ((1, 0), (1, 1)), (0.0, PI / 4)),  # adjacent: θ_r = 0
        (((0, 0), (1, 0)), ((3, 2), (-2, 2)), (PI / 4, 3 * PI / 4)),  # case 1
        (((0, 0), (2, 0)), ((2, 1), (0, 1)), (PI / 2, PI / 2)),  # case 3: singleton
        (((0, 0), (4, 0)), ((3, 1), (1, 1)), None),  # case 2: θ_l = π/4 < θ_r = 3π/4
        (((3, 1), (1, 1)), ((0, 0), (4, 0)), (PI / 4, 3 * PI / 4)),  # case 1
        (((1, 1), (-1, 1)), ((-2, -2), (2, -2)), (math.atan(3), PI - math.atan(3))),
    ],
)
def test_prop2_safe_interval_cases(seg_i, seg_j, expected):
    got = safe_interval(seg_i, seg_j)
    if expected is None:
        assert got is None
    else:
        assert got == pytest.approx(expected, abs=1e-12)


def test_prop2_shared_vertex_special_cases_and_wmin():
    # v_{j+1} = v_i: θ_l = π exactly (the left neighbour across a convex vertex)
    assert safe_interval(((1, 0), (1, 1)), ((0, 0), (1, 0))) == pytest.approx((3 * PI / 4, PI))
    assert safe_interval(((0, 0), (1, 0)), ((1, 0), (1, 1)))[0] == 0.0
    assert safe_interval(((0, 0), (2, 0)), ((2, 1), (0, 1)), w_min=1e-6) is None  # singleton
    assert safe_interval(((1, 1), (-1, 1)), ((-2, -2), (2, -2)))[0] == pytest.approx(1.2490, 1e-4)
    assert safe_interval(((1, 1), (-1, 1)), ((-2, -2), (2, -2)))[1] == pytest.approx(1.8925, 1e-4)


# -- partitions and BVG arc lists of the authors' test polygons -----------------------------------
def test_convex_pentagon_partition_is_identity_and_bvg_complete():
    world = worlds.get("regular_5")
    part = partition(world)
    assert part.n == 5 and not part.inserted.any()
    np.testing.assert_allclose(part.start, world.outer)
    g = bvg(part)
    assert g.number_of_edges() == 20


def test_simple_nonconv_partition_and_bvg():
    part = partition(worlds.get("simple_nonconv"))
    expected = [(250, 250), (0, 100), (-250, 250), (-250, -50), (-250, -250), (250, -250),
                (250, -50)]
    np.testing.assert_allclose(part.start, expected, atol=1e-9)
    assert np.flatnonzero(part.inserted).tolist() == [3, 6]
    assert np.flatnonzero(part.reflex).tolist() == [1]
    g = bvg(part)
    arcs = _adjacency("0→3,4,5,6; 1→2,3,4,5; 2→1,4,5,6; 3→0,1,4,5,6; 4→0,1,2,3,5,6; "
                      "5→0,1,2,3,4; 6→0,2,3,4")
    assert len(arcs) == 32
    assert set(g.edges) == arcs


def test_pinched_square_partition_and_bvg():
    part = partition(worlds.get("pinched_square"))
    expected = [(250, 250), (187.5, 250), (62.5, 250), (-62.5, 250), (-187.5, 250), (-250, 250),
                (-100, 150), (-500 / 3, -250 / 9), (-250, -250), (250, -250), (500 / 3, -250 / 9),
                (100, 150)]
    np.testing.assert_allclose(part.start, expected, atol=1e-9)
    g = bvg(part)
    arcs = _adjacency("0→5,6,7,11; 1→5,6,7,8,11; 2→5..11; 3→5,8,9,10,11; 4→5,9,10,11; "
                      "5→0..4,10,11; 6→0,1,2,8..11; 7→0,1,2,8,9,10; 8→1,2,3,6,7,9,10; "
                      "9→2,3,4,6,7,8; 10→2..8; 11→0..6")
    assert len(arcs) == 72
    assert set(g.edges) == arcs
    # closed sight lines add the isolated grazing line (187.5, 250)-(100, 150)-(-250, -250)
    closed = set(bvg(part, closed=True).edges)
    assert closed - arcs == {(0, 8), (8, 0), (4, 8), (8, 4)}


def test_l_shape_partition():
    part = partition(worlds.get("l_shape"))
    inserted = part.start[part.inserted]
    np.testing.assert_allclose(
        inserted, [(260, 0), (520, 0), (0, 405.88235294), (0, 230)], atol=1e-6
    )
    assert part.n == 10


# -- §7.1.2 Fig. 10 (simple_bit) and Figs. 11-13 (two rooms) --------------------------------------
SIMPLE_BIT = [(250, 250), (24.1935, 88.7097), (-100, 0), (-250, 250), (-250, 60),
              (-250, -107.1429), (-250, -250), (-5.1020, -158.1633), (150, -100), (250, -250),
              (250, -140), (250, -62.5)]

TWO_ROOMS = [(0, 0), (2, 0), (8, 0), (8, 2), (14.75, 2.75), (17, 3), (21.6, -1.6), (23.9, 0.7),
             (1326 / 55, 10 / 11), (24.96, 1.76), (27.08, 3.88), (27.2, 4), (27.08, 4.12),
             (24.96, 6.24), (1326 / 55, 78 / 11), (23.9, 7.3), (21.6, 9.6), (17, 5),
             (14.75, 5.25), (8, 6), (8, 8), (2, 8), (0, 8), (0, 62 / 9), (0, 20 / 3), (0, 4 / 3),
             (0, 10 / 9)]


@pytest.fixture(scope="module")
def simple_bit():
    part = partition(worlds.get("simple_bit"))
    return part, safe_graph(part)


@pytest.fixture(scope="module")
def two_rooms():
    part = partition(worlds.get("two_rooms"))
    return part, safe_graph(part)


def test_simple_bit_fig10(simple_bit):
    part, g = simple_bit
    np.testing.assert_allclose(part.start, SIMPLE_BIT, atol=1e-4)
    arcs = _adjacency("0→5,6,11; 1→5,6,7,11; 2→3,6; 3→2,6; 4→2,6; 5→2,6,11; 6→5,11; "
                      "7→0,4,5,11; 8→0,9; 9→0,8; 10→0,1,8; 11→0,8")
    assert len(arcs) == 31
    assert set(g.edges) == arcs
    # Prop. 5 (§7.3): node 10 (v10 v11) has no incoming safe arc, and both ends are not convex
    reach = reachability(g, part)
    assert reach.unreachable == [10]
    assert part.inserted[10] and part.inserted[11]
    assert reach.unreachable_fraction == pytest.approx(77.5 / part.perimeter)


def test_two_rooms_partition_and_statistics(two_rooms):
    part, g = two_rooms
    np.testing.assert_allclose(part.start, TWO_ROOMS, atol=1e-9)
    assert g.number_of_edges() == 126
    reach = reachability(g, part)
    assert reach.unreachable == [7, 14]  # Prop. 5, closed visibility
    assert reach.n_sccs == 3
    assert reach.n_wccs == 1


def _path_interval(g, path):
    lo = max(g.edges[a, b]["lo"] for a, b in zip(path, path[1:], strict=False))
    hi = min(g.edges[a, b]["hi"] for a, b in zip(path, path[1:], strict=False))
    return lo, hi


def test_two_rooms_published_intervals(two_rooms):
    _, g = two_rooms
    # constant strategy e5 -> e4 along 5→6→12→16→4, and the narrower BFS alternative (§7.1.2)
    assert _path_interval(g, [5, 6, 12, 16, 4]) == pytest.approx((0.0363, 0.1767), abs=1e-4)
    assert _path_interval(g, [5, 6, 11, 16, 4]) == pytest.approx((0.0, 0.0214), abs=1e-4)
    # fewest transitions e0 -> e16 (the paper prints rounded-down values: 1e-4 tolerance)
    for (a, b), iv in {(0, 17): (0.3217, 0.3419), (17, 6): (2.4668, 2.6949),
                       (6, 16): (1.0382, 1.3940), (0, 18): (0.3906, 0.6435),
                       (18, 9): (3.0073, PI), (9, 16): (1.5494, 1.9696),
                       (23, 9): (1.3767, 1.4601), (25, 12): (1.6815, 1.7649)}.items():
        assert (g.edges[a, b]["lo"], g.edges[a, b]["hi"]) == pytest.approx(iv, abs=1.5e-4)
    assert g.edges[0, 17]["width"] == pytest.approx(0.0202, abs=1e-4)


# -- Prop. 3 (§5) on random simple polygons -------------------------------------------------------
@pytest.mark.parametrize("seed", range(6))
def test_prop3_two_safe_actions_on_random_polygons(seed):
    rng = np.random.default_rng(seed)
    world = random_star_polygon(rng, 20, irregularity=0.1 + 0.05 * seed, spikiness=0.3)
    part = partition(world)
    g = safe_graph(part)
    for node in g:
        out = [g.edges[node, k] for k in g.successors(node)]
        assert any(abs(a["lo"]) <= 1e-6 for a in out), node
        assert any(abs(a["hi"] - PI) <= 1e-6 for a in out), node


def test_intervals_out_of_a_node_are_disjoint(two_rooms):
    _, g = two_rooms
    for node in g:
        ivs = sorted((g.edges[node, k]["lo"], g.edges[node, k]["hi"]) for k in g.successors(node))
        for (_, hi), (lo, _) in zip(ivs, ivs[1:], strict=False):
            assert lo >= hi - 1e-9


# -- Def. 7: safety is real -----------------------------------------------------------------------
@pytest.mark.parametrize("name", ["two_rooms", "simple_bit"])
def test_safe_arcs_hold_under_ray_casting(name, two_rooms, simple_bit):
    part, g = two_rooms if name == "two_rooms" else simple_bit
    rng = np.random.default_rng(1)
    arcs = list(g.edges(data=True))
    n = 150
    src = np.repeat([a for a, _, _ in arcs], n)
    dst = np.repeat([b for _, b, _ in arcs], n)
    lo = np.repeat([d["lo"] for _, _, d in arcs], n)
    hi = np.repeat([d["hi"] for _, _, d in arcs], n)
    margin = 1e-3
    s = rng.uniform(margin, 1 - margin, len(src)) * part.length[src]
    theta = lo + (hi - lo) * rng.uniform(margin, 1 - margin, len(src))
    origins = part.start[src] + s[:, None] * part.tangent[src]
    directions = (np.cos(theta)[:, None] * part.tangent[src]
                  + np.sin(theta)[:, None] * part.normal[src])
    hits = part.world.first_hit(origins, directions)
    assert np.all(hits.edge >= 0)
    points = origins + hits.distance[:, None] * directions
    landed = part.locate(hits.edge, points)
    wrong = np.flatnonzero(landed != dst)
    assert len(wrong) == 0, [(int(src[k]), int(dst[k]), int(landed[k])) for k in wrong[:5]]


# -- geometric invariance -------------------------------------------------------------------------
def _arc_data(g):
    return {(a, b): (d["lo"], d["hi"], d["width"]) for a, b, d in g.edges(data=True)}


@pytest.mark.parametrize("name", ["two_rooms", "simple_bit"])
def test_rotation_translation_scale_invariance(name):
    world = worlds.get(name)
    base = _arc_data(safe_graph(partition(world)))
    angle, scale = 0.7, 3.5
    rot = scale * np.array([[math.cos(angle), -math.sin(angle)],
                            [math.sin(angle), math.cos(angle)]])
    moved = _rotated_world(world, rot, shift=(123.0, -45.0))
    part = partition(moved)
    assert part.n == partition(world).n
    got = _arc_data(safe_graph(part))
    assert got.keys() == base.keys()
    for key, val in base.items():
        assert got[key] == pytest.approx(val, abs=1e-9)


@pytest.mark.parametrize("name", ["two_rooms", "simple_bit", "pinched_square"])
def test_mirror_maps_graph_to_mirrored_graph(name):
    world = worlds.get(name)
    part = partition(world)
    g = safe_graph(part)
    mirrored = _rotated_world(world, np.diag([-1.0, 1.0]))
    mpart = partition(mirrored)
    mg = safe_graph(mpart)
    assert mpart.n == part.n
    flip = np.array([-1.0, 1.0])
    # segment k = (a, b) becomes the mirrored segment (flip b, flip a)
    index = {}
    for k in range(part.n):
        d = np.hypot(*(mpart.start - part.end[k] * flip).T)
        index[k] = int(np.argmin(d))
        assert d[index[k]] < 1e-9
    mapped = {(index[a], index[b]): (PI - d["hi"], PI - d["lo"]) for a, b, d in g.edges(data=True)}
    got = {(a, b): (d["lo"], d["hi"]) for a, b, d in mg.edges(data=True)}
    assert got.keys() == mapped.keys()
    for key, val in mapped.items():
        assert got[key] == pytest.approx(val, abs=1e-9)
    assert {(index[a], index[b]) for a, b in bvg(part).edges} == set(bvg(mpart).edges)


# -- holes (§4; docs/choices/visibility.md, "Holes inside the convex hull") ----------------------------------
def test_square_with_hole():
    world = World([(0, 0), (10, 0), (10, 10), (0, 10)],
                  holes=[[(4, 4), (6, 4), (6, 6), (4, 6)]])
    part = partition(world)
    assert part.ring.tolist().count(1) == 4  # the hole's convex corners shoot nothing
    assert part.n == 24  # each hole corner's edge extensions split the outer walls
    vis = visibility_matrix(part)
    bottom = int(np.argmin(np.hypot(*(part.start - (4.0, 0.0)).T)))  # (4,0)-(6,0)
    top = int(np.argmin(np.hypot(*(part.start - (6.0, 10.0)).T)))  # (6,10)-(4,10)
    assert not vis[bottom, top]  # the hole sits inside their convex hull
    g = safe_graph(part)
    assert not g.has_edge(bottom, top)
    for node in g:  # Prop. 3 holds on the outer ring and on the hole
        out = [g.edges[node, k] for k in g.successors(node)]
        assert any(abs(a["lo"]) <= 1e-6 for a in out)
        assert any(abs(a["hi"] - PI) <= 1e-6 for a in out)


# -- the BVG against sampled sight lines ---------------------------------------------------------
def _sampled_arcs(part, samples: int = 7) -> set[tuple[int, int]]:
    """Pairs (i, j) joined by one of samples² open sight lines between interior points of e_i
    and e_j that leave both segments into free space (`visible_pairs` with closed=False)."""
    t = np.linspace(0.05, 0.95, samples)
    i, j, s, u = (x.ravel() for x in np.meshgrid(np.arange(part.n), np.arange(part.n), t, t,
                                                  indexing="ij"))
    keep = i != j
    i, j, s, u = i[keep], j[keep], s[keep], u[keep]
    p = part.start[i] + s[:, None] * (part.end[i] - part.start[i])
    q = part.start[j] + u[:, None] * (part.end[j] - part.start[j])

    def left(k, x):
        rel = x - part.start[k]
        return part.tangent[k, 0] * rel[:, 1] - part.tangent[k, 1] * rel[:, 0] > part.tol

    ok = left(i, q) & left(j, p)
    ok[ok] = visible_pairs(part.world, p[ok], q[ok], closed=False,
                           exclude_points=part.start)
    return set(zip(i[ok].tolist(), j[ok].tolist(), strict=True))


@pytest.mark.parametrize("seed", range(4))
def test_bvg_contains_sampled_sight_lines_and_the_safe_graph(seed):
    """The all-pairs BVG (one array of candidate lines for every pair at once) has an arc
    wherever a sampled sight line joins two segments; the Def. 5 (open) arcs are a subset of the
    closed ones, and G_safe's arcs (entire visibility) are BVG arcs."""
    rng = np.random.default_rng(seed)
    world = random_star_polygon(rng, 12 + 4 * seed, irregularity=0.3, spikiness=0.4)
    if seed == 3:
        world = World([(0, 0), (10, 0), (10, 10), (0, 10)],
                      holes=[[(4, 4), (6, 4), (6, 6), (4, 6)]])
    part = partition(world)
    closed, opened = set(bvg(part, closed=True).edges), set(bvg(part).edges)
    sampled = _sampled_arcs(part)
    assert sampled and sampled <= closed
    assert sampled <= opened
    assert opened <= closed
    assert set(safe_graph(part).edges) <= opened
