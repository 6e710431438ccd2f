"""Visibility-based distributed (§4.3.3) and centralised (§4.3.4) patrol subsets, and the
centralised detection-time starts (§4.3.5) (Alam 2018, thesis ch. 4)."""

import math

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.base_station import kept_overlap
from baselines.patrolling.graphs import cell_graph
from baselines.patrolling.markov import transition_matrix
from baselines.patrolling.visibility import cell_visibility, complete_visibility, watch_region
from baselines.patrolling.visibility_policies import (
    centralised_plan,
    centralised_starts,
    distributed_subsets,
)
from baselines.patrolling.vulnerability import detection_times
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World, zoo
from bounce_gym.worlds.grid import world_from_grid

MAPS = {"patrol_15x15": 188, "patrol_18x16": 253}


def _setting(world, cell_size=1.0):
    return cell_graph(world, cell_size), cell_visibility(world.occupancy(cell_size), 6)


@pytest.fixture(scope="module", params=sorted(MAPS))
def case(request):
    graph, vis = _setting(zoo.get(request.param))
    assert len(vis) == MAPS[request.param]
    return request.param, graph, vis, centralised_plan(graph, vis, vis, 3)


def _seen_by(vis, centres):
    seen = np.zeros(len(vis), dtype=bool)
    for z in centres:
        seen[vis.visible_from(z)] = True
    return seen


def _neighbours(vis, v):
    r, c = vis.cells[v]
    near = np.abs(vis.cells - (r, c)).max(axis=1) == 1
    return np.flatnonzero(near)


@pytest.mark.parametrize("name", sorted(MAPS))
def test_distributed_subsets_are_alg_4_3_covers_each_seeing_every_cell(name):
    _, vis = _setting(zoo.get(name))
    subsets = distributed_subsets(vis, 2)
    assert subsets == complete_visibility(vis, 2)
    for subset in subsets:
        assert _seen_by(vis, subset).all()
        assert len(set(subset)) == len(subset)


def test_regions_partition_the_patrol_cells(case):
    _, _, vis, plan = case
    owner = np.full(len(vis), -1)
    for i, region in enumerate(plan.regions):
        assert (owner[list(region)] == -1).all()  # no cell in two regions
        owner[list(region)] = i
    unpatrolled = set(np.flatnonzero(owner == -1).tolist())
    assert unpatrolled == set(plan.monitored)
    assert set(plan.monitored) <= set(plan.comm_region)
    kept = set().union(*map(set, plan.overlap))
    assert kept | set(plan.monitored) == set(plan.comm_region)
    assert not kept & set(plan.monitored)
    assert plan.comm_region == tuple(vis.visible_from(plan.base_station).tolist())


def test_overlap_cells_ring_the_comm_region_within_each_sector(case):
    _, _, vis, plan = case
    comm = set(plan.comm_region)
    sector = np.array(plan.sectors)
    for i, (region, ring) in enumerate(zip(plan.regions, plan.overlap, strict=True)):
        assert len(ring) >= 1
        assert set(ring) == set(region) & comm
        assert (sector[list(region)] == i).all()
    for v in plan.comm_region:
        outside_same_sector = [u for u in _neighbours(vis, v)
                               if u not in comm and sector[u] == sector[v]]
        assert (v in plan.monitored) == (not outside_same_sector)


def test_three_robots_get_sectors_of_120_degrees(case):
    _, _, vis, plan = case
    assert plan.sector_width == 120.0
    by, bx = vis.cells[plan.base_station]
    for v, (y, x) in enumerate(vis.cells):
        theta = math.degrees(math.atan2(y - by, x - bx)) % 360
        assert plan.sectors[v] == int(theta // 120)
    assert set(plan.sectors) == {0, 1, 2}


def test_base_station_is_the_best_seeing_cell_near_the_centroid(case):
    _, _, vis, plan = case
    centres = vis.cells[:, ::-1] + 0.5
    assert plan.centroid == pytest.approx(tuple(centres.mean(axis=0)))
    distance = np.hypot(*(centres - plan.centroid).T)
    assert distance[plan.base_station] <= plan.r / 2
    assert plan.candidates == tuple(np.flatnonzero(distance <= plan.r / 2).tolist())
    counts = {v: len(vis.visible_from(v)) for v in plan.candidates}
    assert counts[plan.base_station] == max(counts.values())


def test_covers_contacts_and_subsets(case):
    _, _, vis, plan = case
    for region, ring, cover, contact, subset in zip(plan.regions, plan.overlap, plan.covers,
                                                    plan.contacts, plan.subsets, strict=True):
        assert set(cover) <= set(region)
        assert _seen_by(vis, cover)[list(region)].all()
        assert contact in ring
        gap = {o: min(math.dist(vis.cells[o], vis.cells[c]) for c in cover) for o in ring}
        assert gap[contact] == min(gap.values())
        assert set(subset) == set(cover) | {contact} and len(set(subset)) == len(subset)


def test_plan_is_deterministic_and_takes_r_as_a_number(case):
    _, graph, vis, plan = case
    assert centralised_plan(graph, vis, vis, 3) == plan
    assert centralised_plan(graph, 6, vis, 3) == plan
    assert centralised_plan(graph, 6, vis, 3, confine_to_region=True).confine_to_region


@pytest.mark.parametrize("name", sorted(MAPS))
def test_plan_does_not_depend_on_where_the_map_lies_or_its_scale(name):
    world = zoo.get(name)
    scale, shift = 1e-3, 1e5
    moved = World(world.outer * scale + shift, [h * scale + shift for h in world.holes])
    graph, vis = _setting(world)
    moved_graph, moved_vis = _setting(moved, scale)
    assert np.array_equal(moved_vis.cells, vis.cells)
    assert centralised_plan(moved_graph, moved_vis, moved_vis, 3) == \
        centralised_plan(graph, vis, vis, 3)
    assert distributed_subsets(moved_vis, 2) == distributed_subsets(vis, 2)


def test_cells_on_a_sector_boundary_ray_open_the_next_sector():
    graph, vis = _setting(world_from_grid(np.ones((21, 21), dtype=bool)))
    plan = centralised_plan(graph, 4, vis, 4)
    by, bx = vis.cells[plan.base_station]
    sector = dict(zip(map(tuple, vis.cells.tolist()), plan.sectors, strict=True))
    assert (by, bx) == (10, 10) and sector[(by, bx)] == 0
    assert [sector[(by, bx + 5)], sector[(by + 5, bx)], sector[(by, bx - 5)],
            sector[(by - 5, bx)]] == [0, 1, 2, 3]


def test_centralised_starts_are_outside_t_in_each_robots_region(case):
    _, graph, vis, plan = case
    watch = watch_region(vis, plan.covers[0][0])
    starts = centralised_starts(plan, watch)
    for start, region in zip(starts, plan.regions, strict=True):
        assert start and set(start) == set(region) - set(watch.inside.tolist())
    walk, nodes = transition_matrix(graph, nodes=sorted(graph))
    times = detection_times([walk] * 3, watch.boundary, nodes=nodes, starts=starts,
                            per_robot_starts=True, n_runs=200, seed=1)
    assert (times >= 1).all() and np.isfinite(times).all()


def test_bad_input_raises_config_error_naming_the_argument():
    graph, vis = _setting(zoo.get("patrol_15x15"))
    with pytest.raises(ConfigError, match="^m"):
        centralised_plan(graph, vis, vis, 0)
    with pytest.raises(ConfigError, match="^m"):
        distributed_subsets(vis, 0)
    for r in (0, -1.0, float("nan")):
        with pytest.raises(ConfigError, match="^visibility_r"):
            centralised_plan(graph, r, vis, 3)
    with pytest.raises(ConfigError, match="^visibility_l"):
        centralised_plan(graph, vis, None, 3)
    with pytest.raises(ConfigError, match="^visibility"):
        distributed_subsets(graph, 2)
    with pytest.raises(ConfigError, match="^visibility_r"):
        centralised_plan(graph, cell_visibility(np.ones((3, 3), dtype=bool), 2), vis, 3)
    with pytest.raises(ConfigError, match="^graph"):
        centralised_plan(nx.path_graph(len(vis)), vis, vis, 3)
    with pytest.raises(ConfigError, match="^confine_to_region"):
        centralised_plan(graph, vis, vis, 3, confine_to_region="yes")
    plan = centralised_plan(graph, vis, vis, 3)
    with pytest.raises(ConfigError, match="^plan"):
        centralised_starts(vis, watch_region(vis, 0))
    with pytest.raises(ConfigError, match="^watch"):
        centralised_starts(plan, 0)


def test_a_sector_without_cells_outside_the_base_stations_range_is_refused():
    small, small_vis = _setting(world_from_grid(np.ones((5, 5), dtype=bool)))
    with pytest.raises(ConfigError, match="^m: sector 0 .* no cells"):
        centralised_plan(small, 6, small_vis, 3)


def test_a_comm_cell_next_only_to_another_sectors_outside_cells_is_left_to_the_base_station():
    cells = np.array([[0, 0], [0, 1], [0, 2], [1, 2], [1, 3]])  # (row, col)
    sector = np.array([0, 0, 1, 0, 0])
    kept = kept_overlap(cells, sector, np.array([0, 1, 3]))
    # cell 1 touches only cell 2 outside (another sector); cell 3 touches cell 4 (its own)
    assert kept.tolist() == [False, False, False, True, False]


def test_a_sector_whose_cells_never_touch_the_base_stations_range_is_refused():
    free = np.zeros((4, 21), dtype=bool)
    free[0, :] = True  # a corridor along the bottom row
    free[1:, 0] = True  # a spur up at its far left end: sector 1 of 4, beyond r = 4
    graph, vis = _setting(world_from_grid(free))
    with pytest.raises(ConfigError, match="^m: sector 1 .* overlap ring"):
        centralised_plan(graph, 4, vis, 4)
