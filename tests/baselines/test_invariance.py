"""Every planner family is invariant to translating and scaling the map (real maps come in metres
of a projected coordinate system, far from the origin): the same plans on a copy of a zoo map
shifted by 10⁵ or by (10⁵, −7·10⁴), or scaled by 10⁻³ or 10³ (the cell size scaled with it).
docs/choices/visibility.md, "Tolerances relative to the polygon's size"."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines.coverage.mixture import coverage_mixture
from baselines.localization.planner import AngleSwitchPlanner, build_policy_dfa
from baselines.multirobot.coverage import plan_coverage
from baselines.multirobot.monitoring import joint_monitoring_cycles
from baselines.navigation.roadmap import Roadmap, goal_cells
from baselines.visibility import planning as P
from baselines.visibility.graph import bvg, safe_graph
from baselines.visibility.partition import partition
from bounce_gym import worlds
from bounce_gym.cells import CellModel, JointCellModel
from bounce_gym.markov.automata import build_dfa
from bounce_gym.worlds import World

#: (scale, shift) of the copies.
TRANSFORMS = [(1.0, (1e5, 1e5)), (1.0, (1e5, -7e4)), (1e-3, (0.0, 0.0)), (1e3, (0.0, 0.0))]
IDS = ["shift-1e5", "shift-1e5,-7e4", "scale-1e-3", "scale-1e3"]


def transformed(world: World, scale: float, shift) -> World:
    """The world's rings scaled about the origin, then shifted."""
    t = np.asarray(shift, dtype=np.float64)
    return World(world.outer * scale + t, [h * scale + t for h in world.holes],
                 name=f"{world.name}-moved")


def _arcs(g):
    return {(u, v): (d["lo"], d["hi"]) for u, v, d in g.edges(data=True)}


@pytest.fixture(scope="module")
def visibility_originals():
    out = {}
    for name in ("lab_fig1", "two_rooms", "heptagon"):
        part = partition(worlds.get(name))
        out[name] = part, safe_graph(part)
    return out


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
@pytest.mark.parametrize("name", ["lab_fig1", "two_rooms", "heptagon"])
def test_visibility_partition_and_safe_graph(visibility_originals, name, scale, shift):
    """Before the fix, lab_fig1 shifted by 10⁵ lost the arc 43 → 19 (its far segment starts on
    the near segment's line: a −1e-11 rad rounding wrapped θ_r to π)."""
    part, g = visibility_originals[name]
    part2 = partition(transformed(part.world, scale, shift))
    assert part2.n == part.n
    assert np.allclose((part2.start - np.asarray(shift)) / scale, part.start, atol=1e-6)
    g2 = safe_graph(part2)
    arcs, arcs2 = _arcs(g), _arcs(g2)
    assert set(arcs2) == set(arcs)
    for key, (lo, hi) in arcs.items():
        assert arcs2[key] == pytest.approx((lo, hi), abs=1e-7)


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
def test_visibility_bvg_plans_and_patrol(visibility_originals, scale, shift):
    part, g = visibility_originals["two_rooms"]
    part2 = partition(transformed(part.world, scale, shift))
    g2 = safe_graph(part2)
    assert set(bvg(part2).edges) == set(bvg(part).edges)
    for start, goal in ((0, 16), (3, 9)):
        plan, plan2 = P.fewest_bounce_plan(g, start, goal), P.fewest_bounce_plan(g2, start, goal)
        assert plan2.path == plan.path
        assert np.allclose(plan2.intervals, plan.intervals, atol=1e-7)
    part, g = visibility_originals["heptagon"]
    part2 = partition(transformed(part.world, scale, shift))
    g2 = safe_graph(part2)
    edges = list(range(7))
    cyc = P.patrol(g, part, edges, max_len=9, start=0, theta=0.1)
    cyc2 = P.patrol(g2, part2, edges, max_len=9, start=0, theta=0.1)
    assert cyc2.cycle == cyc.cycle and cyc2.approach.path == cyc.approach.path
    assert cyc2.coefficient == pytest.approx(cyc.coefficient, rel=1e-6)
    points = (cyc2.fixed_point.points - np.asarray(shift)) / scale
    assert np.allclose(points, cyc.fixed_point.points, atol=1e-6 * part.world.diameter)


def _models(name: str, scale: float, shift, **kwargs) -> tuple[CellModel, CellModel]:
    world = worlds.get(name)
    return (CellModel(world, **kwargs),
            CellModel(transformed(world, scale, shift), cell_size=scale, **kwargs))


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
@pytest.mark.parametrize("name", ["lab_navigation", "lab_fig1", "grid_10x10", "two_rooms"])
def test_cell_model(name, scale, shift):
    """The discrete model every cell-based family plans on is the same grid."""
    model, model2 = _models(name, scale, shift)
    assert np.array_equal(model2.free, model.free)
    assert np.array_equal(model2.targets, model.targets)
    z = np.arange(model.n_cells)
    pos, head = model2.configuration(z)
    assert np.array_equal(model2.cell_of(pos, head), z)
    assert np.allclose((pos - np.asarray(shift)) / scale, model.centres[model.decode(z)[0]])


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
def test_navigation_roadmap_plans(scale, shift):
    model, model2 = _models("lab_navigation", scale, shift)
    rm, rm2 = Roadmap(model, [45, 90, 135]), Roadmap(model2, [45, 90, 135])
    for start, (x, y, heading) in ((0, (11.5, 5.5, 0.0)), (40, (3.5, 0.5, math.pi))):
        goal = goal_cells(model, (x, y), heading, radius=1.0, tolerance=math.radians(10))
        goal2 = goal_cells(model2, (x * scale + shift[0], y * scale + shift[1]), heading,
                           radius=1.0 * scale, tolerance=math.radians(10))
        assert np.array_equal(goal2, goal) and len(goal) > 1
        plan, plan2 = rm.plan(start, goal), rm2.plan(start, goal2)
        assert plan2 == plan and plan2.weight == plan.weight


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
def test_coverage_mixture(scale, shift):
    model, model2 = _models("lab_fig1", scale, shift, n_bins=72)  # 5° bins
    angles, eps = np.radians([30, 75, 315]), math.radians(5)
    a = coverage_mixture(model, angles, eps, 0.8)
    a2 = coverage_mixture(model2, angles, eps, 0.8)
    assert np.array_equal(a2.alpha, a.alpha) and a2.residual == a.residual


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
def test_localization_dfa_sizes(scale, shift):
    model, model2 = _models("lab_localization_a", scale, shift)
    for phi in (45, 135):
        d, d2 = (build_dfa(*m.successor(math.radians(phi))) for m in (model, model2))
        assert (d2.n_states, d2.cycle_lengths) == (d.n_states, d.cycle_lengths)
    p, p2 = (build_policy_dfa(AngleSwitchPlanner(m, np.radians([45, 135]))) for m in (model, model2))
    assert (p2.n_states, p2.cycle_lengths) == (p.n_states, p.cycle_lengths)


@pytest.mark.parametrize(("scale", "shift"), TRANSFORMS, ids=IDS)
def test_multirobot_coverage_and_monitoring(scale, shift):
    model, model2 = _models("grid_10x10", scale, shift, corner_rule="no_squeeze")
    jm, jm2 = JointCellModel(model, [135] * 3), JointCellModel(model2, [135] * 3)
    x0 = jm.random_joint(np.random.default_rng(0))[0]
    res, res2 = plan_coverage(jm, x0, max_steps=3000), plan_coverage(jm2, x0, max_steps=3000)
    assert res2.steps_to_full == res.steps_to_full and res2.collisions == res.collisions
    assert np.array_equal(np.array(res2.trajectory), np.array(res.trajectory))
    phi = math.radians(90)
    mon, mon2 = (joint_monitoring_cycles(m, [phi, phi]) for m in (model, model2))
    assert mon2.r == mon.r
    assert np.array_equal(mon2.accepted, mon.accepted) and np.array_equal(mon2.label, mon.label)
