"""Safe planning, patrolling, plan execution and figures (Nilles et al. 2021, §7.1–7.2
and §7.1.2; choices in docs/choices/visibility.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines.visibility import planning as P
from baselines.visibility.graph import safe_graph
from baselines.visibility.partition import partition
from bounce_gym import worlds
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym_experiments.plots.visibility import (
    plot_limit_cycle,
    plot_partition,
    plot_plan_cone,
    plot_safe_graph,
)


@pytest.fixture(scope="module")
def two_rooms():
    world = worlds.get("two_rooms")
    part = partition(world)
    return world, part, safe_graph(part)


def _check_intervals(got, expected, tol):
    assert len(got) == len(expected)
    for (lo, hi), (elo, ehi) in zip(got, expected, strict=True):
        assert lo == pytest.approx(elo, abs=tol)
        assert hi == pytest.approx(ehi, abs=tol)


def _assert_safe(world, part, plan, g, n=300, seed=0):
    """Def. 7: every stage's arc is in G_safe, the stage interval lies in the arc's interval, and
    rays from random points with random angles in it hit the next segment."""
    rng = np.random.default_rng(seed)
    for k, (lo, hi) in enumerate(plan.intervals):
        for u in plan.stages[k]:
            nxt = [v for v in plan.stages[k + 1] if g.has_edge(u, v)
                   and g.edges[u, v]["lo"] <= lo + 1e-12 and hi <= g.edges[u, v]["hi"] + 1e-12]
            assert nxt, f"stage {k}: no safe arc from {u} covering ({lo}, {hi})"
            v = nxt[0]
            s = rng.uniform(0, part.length[u], n)
            th = rng.uniform(lo, hi, n)
            th = np.clip(th, np.nextafter(lo, hi), np.nextafter(hi, lo))
            p = part.start[u] + s[:, None] * part.tangent[u]
            d = np.cos(th)[:, None] * part.tangent[u] + np.sin(th)[:, None] * part.normal[u]
            hits = world.first_hit(p, d)
            seg = part.locate(hits.edge, p + hits.distance[:, None] * d)
            assert np.all(seg == v)


# -- §7.1.2 published two-room numbers ------------------------------------------------------------

def test_constant_strategy_e5_e4(two_rooms):
    """§7.1.2: θ̃ = (0.0363, 0.1767) along 5→6→12→16→4 (widest tie-break: docs/choices/visibility.md, "Ties
    among shortest safe plans")."""
    world, part, g = two_rooms
    for order in ("shortest", "widest"):
        plan = P.constant_strategy(g, 5, 4, max_arcs=4, order=order)
        assert plan is not None and plan.kind == "constant"
        assert plan.path == [5, 6, 12, 16, 4]
        assert round(plan.constant[0], 4) == 0.0363
        assert round(plan.constant[1], 4) == 0.1767
        assert plan.width == pytest.approx(plan.constant[1] - plan.constant[0])
        assert all(iv == plan.constant for iv in plan.intervals)
    # too few arcs: no constant strategy
    assert P.constant_strategy(g, 5, 4, max_arcs=2) is None
    _assert_safe(world, part, plan, g)
    assert P.monte_carlo(world, part, plan, n=2000, seed=1) == 1.0  # §7.1.2: 2000/2000


def test_fewest_transitions_e0_e16(two_rooms):
    """§7.1.2: 0→17→6→16 with (0.3217, 0.3419), (2.4668, 2.6949), (1.0382, 1.3940); the paper
    rounds, so tolerance 1e-3; Monte-Carlo 3000/3000."""
    world, part, g = two_rooms
    plan = P.fewest_bounce_plan(g, 0, 16)
    assert plan.path == [0, 17, 6, 16]
    _check_intervals(plan.intervals, [(0.3217, 0.3419), (2.4668, 2.6949), (1.0382, 1.3940)], 1e-3)
    _assert_safe(world, part, plan, g)
    assert P.monte_carlo(world, part, plan, n=3000, seed=2) == 1.0
    # the "widest minimum interval" tie-break among the 3-arc paths picks the bottleneck path
    assert P.fewest_bounce_plan(g, 0, 16, tie="widest").path == [0, 18, 9, 16]


def test_bottleneck_e0_e16(two_rooms):
    """§7.1.2: bottleneck variant 0→18→9→16, minimum width 0.1343."""
    world, part, g = two_rooms
    plan = P.bottleneck_plan(g, 0, 16, max_arcs=3)
    assert plan.path == [0, 18, 9, 16]
    assert plan.width == pytest.approx(0.1343, abs=1e-4)
    _check_intervals(plan.intervals, [(0.3906, 0.6435), (3.0073, math.pi), (1.5494, 1.9696)],
                     1e-3)
    _assert_safe(world, part, plan, g)
    assert P.monte_carlo(world, part, plan, n=1000, seed=3) == 1.0


def test_unreachable_goal_returns_none(two_rooms):
    """Prop. 5: nodes 7 and 14 of two_rooms have in-degree 0 (§7.3)."""
    _, _, g = two_rooms
    assert P.fewest_bounce_plan(g, 0, 7) is None
    assert P.bottleneck_plan(g, 0, 14, max_arcs=6) is None
    assert P.constant_strategy(g, 0, 7, max_arcs=4) is None


def test_split_and_start_set(two_rooms):
    """docs/choices/visibility.md, "Start and goal sets split the partition": refine P' at S's end points; a
    start set spanning several segments runs the BFS over (set of segments, θ̃)."""
    world, part, _ = two_rooms
    mid = 0.5 * (part.start[5] + part.end[5])
    fine = P.split_at(part, [mid, part.start[5]])  # the vertex is ignored
    assert fine.n == part.n + 1
    g = safe_graph(fine)
    halves = sorted({int(k) for k in fine.locate([part.edge[5]] * 2,
                                                 [part.start[5] * 0.75 + part.end[5] * 0.25,
                                                  part.start[5] * 0.25 + part.end[5] * 0.75])})
    assert len(halves) == 2
    plan = P.constant_strategy(g, halves, 4, max_arcs=4)
    assert plan is not None and plan.stages[0] == tuple(halves)
    assert plan.width >= 0.1403 - 1e-9  # sub-segments see at least the whole segment's θ̃
    _assert_safe(world, fine, plan, g)
    assert P.monte_carlo(world, fine, plan, n=1000, seed=4) == 1.0


# -- patrolling (Def. 15) -------------------------------------------------------------------------

def test_patrol_convex_polygon():
    world = worlds.get("heptagon")
    part = partition(world)
    g = safe_graph(part)
    seq = list(range(world.n_edges))
    plan = P.patrol(g, part, seq, max_len=world.n_edges, start=3, strict=True)
    assert plan is not None and plan.stable and plan.coefficient < 1
    assert list(plan.colours) == seq
    for th, (lo, hi) in zip(plan.thetas, plan.intervals, strict=True):
        assert lo < th < hi
    assert plan.approach is not None and plan.approach.stages[-1][0] in plan.cycle
    # ray casting from a point of the cycle's first segment converges to the predicted cycle
    pts = plan.fixed_point.points
    seg0 = plan.cycle[0]
    p = part.start[seg0] + 0.3 * part.length[seg0] * part.tangent[seg0]
    for _ in range(40):
        for k, node in enumerate(plan.cycle):
            th = plan.thetas[k]
            d = np.cos(th) * part.tangent[node] + np.sin(th) * part.normal[node]
            hit = world.first_hit(p[None], d[None])
            p = p + hit.distance[0] * d
    assert np.allclose(p, pts[0], atol=1e-6)


def test_patrol_l_shape_lower_arm():
    """Prop. 4: θ = 0.2 gives the 4-cycle of the lower 600×230 arm with contacts (22.9099, 0),
    (600, 116.9820), (577.0901, 230), (0, 113.0180)."""
    world = worlds.get("l_shape")
    part = partition(world)
    g = safe_graph(part)
    plan = P.patrol(g, part, [0, 1, 2, 5], max_len=6, theta=0.2, strict=True)
    assert plan is not None and plan.stable and len(plan.cycle) == 4
    expected = np.array([[22.9099, 0], [600, 116.9820], [577.0901, 230], [0, 113.0180]])
    got = plan.fixed_point.points
    k = int(np.argmin(np.linalg.norm(got - expected[0], axis=1)))
    assert np.allclose(np.roll(got, -k, axis=0), expected, atol=1e-4)


# -- execution in the environment -----------------------------------------------------------------

def _run_policy(plan, part, g=None, episodes=100, seed=0):
    env = BounceEnv(world="two_rooms", bounce_rule="fixed", action_type="continuous",
                    angle_range=(0.5, 179.5), step_mode="bounce", backend="kinematic")
    policy = P.PlanPolicy(plan, part, seed=seed, graph=g)
    rng = np.random.default_rng(seed)
    a, b = part.start[plan.path[0]], part.end[plan.path[0]]
    wins, steps = 0, []
    for ep in range(episodes):
        p = a + rng.uniform(0.01, 0.99) * (b - a) + 1e-3 * part.normal[plan.path[0]]
        heading = math.atan2(-part.normal[plan.path[0]][1], -part.normal[plan.path[0]][0])
        obs, info = env.reset(seed=ep, options={"start": {"position": p.tolist(),
                                                          "heading": heading}})
        policy.reset(env)
        assert policy.segment(info) == plan.path[0]
        n = 0
        for _ in range(10):
            action = policy.act(obs, info)
            if policy.reached_goal:
                break
            obs, _, terminated, truncated, info = env.step(action)
            n += 1
            if terminated or truncated:
                break
        policy.act(obs, info)
        wins += policy.reached_goal
        steps.append(n)
    env.close()
    return wins / episodes, steps


def test_plan_policy_reaches_goal(two_rooms):
    """PlanPolicy in BounceEnv(two_rooms, fixed, continuous, (0.5°, 179.5°)) from segment 0 reaches
    segment 16 in every seeded episode, in exactly the plan's three bounces."""
    _, part, g = two_rooms
    for plan in (P.fewest_bounce_plan(g, 0, 16), P.bottleneck_plan(g, 0, 16, 3)):
        rate, steps = _run_policy(plan, part, episodes=100)
        assert rate == 1.0
        assert set(steps) == {3}


def test_plan_policy_rejects_out_of_range(two_rooms):
    _, part, g = two_rooms
    plan = P.bottleneck_plan(g, 0, 16, 3)  # stage 2 is (3.0073, π) = (172.3°, 180°)
    env = BounceEnv(world="two_rooms", bounce_rule="fixed", action_type="continuous",
                    angle_range=(10, 170))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="angle_range"):
        P.PlanPolicy(plan, part).reset(env)
    env.close()


# -- figures --------------------------------------------------------------------------------------

def test_plots_written(two_rooms, tmp_path):
    world, part, g = two_rooms
    plan = P.fewest_bounce_plan(g, 0, 16)
    lpart = partition(worlds.get("l_shape"))
    cyc = P.patrol(safe_graph(lpart), lpart, [0, 1, 2, 5], 6, theta=0.2, strict=True)
    paths = [
        plot_partition(part, tmp_path / "partition.png"),
        plot_safe_graph(g, tmp_path / "gsafe.png"),
        plot_plan_cone(part, plan, tmp_path / "cone.png", n_rays=50),
        plot_limit_cycle(lpart, cyc, tmp_path / "cycle.png"),
    ]
    for p in paths:
        assert p.exists() and p.stat().st_size > 1000
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
