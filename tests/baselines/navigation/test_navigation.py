"""Navigation (issue #5): the layered roadmap, minimum plans, all plans and their execution.

Sources: Alam, Bobadilla & Shell 2017, Sec. III-C (Problems 1-2), Sec. IV-A/B (Algs. 1-2) and
Sec. V-A/B; thesis §3.4.1-3.4.2 and §3.5.1-3.5.2; choices where the paper is open:
docs/choices/navigation_coverage.md. Cells are 0-based here (``z = k·N_pos + p``); the papers' ids are ``z + 1``.
Coordinates are (column, row), origin bottom-left; bins count counter-clockwise from East.
"""

from __future__ import annotations

import math

import networkx as nx
import numpy as np
import pytest

import baselines.navigation.roadmap as roadmap
from baselines.navigation import (
    BUMP,
    FORWARD,
    NavigationPlanner,
    PlanExecutor,
    Roadmap,
    goal_cells,
)
from bounce_gym.cells import CellModel
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import get, world_from_grid

PHI = (45, 90, 135)
E, N, W = 0, 2, 4  # bins of East, North, West with 8 bins


def rect(width: int, height: int, n_bins: int = 8) -> CellModel:
    return CellModel(world_from_grid(np.ones((height, width), dtype=bool)), n_bins=n_bins)


def small_map() -> CellModel:
    """7 x 5 room with a 2 x 1 block in the middle and a notch on the top wall: 30 positions,
    240 cells. Small enough to check all 57 360 ordered pairs."""
    free = np.ones((5, 7), dtype=bool)
    free[2, 2:4] = False
    free[4, 5] = False
    return CellModel(world_from_grid(free), n_bins=8)


def cell(model: CellModel, col: int, row: int, k: int) -> int:
    return int(model.cell_id(model.position_index[row, col], k))


@pytest.fixture(scope="module")
def lab():
    return CellModel(get("lab_navigation"), n_bins=8)


@pytest.fixture(scope="module")
def small():
    model = small_map()
    roadmap = Roadmap(model, PHI)
    return model, roadmap, roadmap.all_pairs()


# -- the roadmap ------------------------------------------------------------------------------

def out_edges(roadmap: Roadmap, node: int) -> list[tuple[int, float, int, int]]:
    """(target node, weight, kind, angle index) of the stored edges leaving ``node``."""
    g = roadmap.graph
    return [(int(g.indices[e]), float(g.data[e]), int(roadmap.edge_kind[e]),
             int(roadmap.edge_angle[e])) for e in range(g.indptr[node], g.indptr[node + 1])]


def test_eq3_steps_and_the_blocked_step_are_roadmap_edges():
    """Eq. 3: from an open centroid θ = 0 → (c+1, r), 45° → (c+1, r+1), 90° → (c, r+1),
    as forward edges (symbol 0) that keep the bin. A bump (docs/choices/cell_model.md, "Bumps rotate in place
    and take one tick"): at the East wall facing East with
    φ = 90° the robot stays and faces North; the plan's symbol is 90."""
    model = rect(5, 4)
    rm = Roadmap(model, [90])
    for k, (col, row) in ((0, (3, 1)), (1, (3, 2)), (2, (2, 2))):
        edges = out_edges(rm, rm.node(cell(model, 2, 1, k), 0))
        assert edges == [(rm.node(cell(model, col, row, k), 0), 1.0, FORWARD, -1)]
    wall = cell(model, 4, 1, E)
    assert out_edges(rm, rm.node(wall, 0)) == [(rm.node(cell(model, 4, 1, N), 0), 1.0, BUMP, 0)]
    plan = rm.plan(wall, cell(model, 4, 1, N))
    assert plan.symbols == (90,) and plan.cells == (wall, cell(model, 4, 1, N))
    assert (plan.weight, plan.ticks, plan.angle_changes) == (1.0, 1, 0)


def test_layered_out_degrees(lab):
    """The layered roadmap (docs/choices/navigation_coverage.md, "The roadmap remembers the current bounce angle"):
    a bump cell has out-degree |Φ| in every layer, one w1 edge that keeps the
    layer and |Φ| − 1 w2 edges into the other layers; a forward cell has out-degree 1 (w1,
    same layer, same bin)."""
    rm = Roadmap(lab, PHI)
    assert rm.n_nodes == 3 * 384 and rm.graph.shape == (1152, 1152)
    p, k = lab.decode(np.arange(lab.n_cells))
    blocked = lab.targets[k, p] < 0
    assert 0 < blocked.sum() < lab.n_cells
    degree = rm.out_degree()
    for i in range(3):
        np.testing.assert_array_equal(degree[i * 384:(i + 1) * 384], np.where(blocked, 3, 1))
    for z in (int(np.flatnonzero(blocked)[5]), int(np.flatnonzero(~blocked)[5])):
        for i in range(3):
            edges = out_edges(rm, rm.node(z, i))
            if blocked[z]:
                assert sorted(e[3] for e in edges) == [0, 1, 2]
                for target, weight, kind, angle in edges:
                    cz, layer = rm.split(target)
                    assert kind == BUMP and layer == angle
                    assert weight == (1.0 if angle == i else 100.0)
                    np.testing.assert_array_equal(
                        lab.decode(cz), (lab.decode(z)[0], (lab.decode(z)[1] + angle + 1) % 8))
            else:
                [(target, weight, kind, angle)] = edges
                assert (kind, angle, weight) == (FORWARD, -1, 1.0)
                assert rm.split(target)[1] == i and lab.decode(rm.split(target)[0])[1] == k[z]
    assert rm.graph.has_sorted_indices and len(rm.graph.data) == len(rm.edge_kind)


def test_counts(lab):
    """Sec. V / thesis §3.5: N = N_pos · n_θ for the navigation maps (384 = 48·8, 1464 = 183·8)."""
    assert (lab.n_positions, lab.n_cells) == (48, 384)
    complex_ = CellModel(get("lab_complex"), n_bins=8)
    assert (complex_.n_positions, complex_.n_cells) == (183, 1464)


def test_roadmap_validation(lab):
    with pytest.raises(ConfigError, match="bins"):
        Roadmap(lab, [30])
    with pytest.raises(ConfigError, match="distinct"):
        Roadmap(lab, [90, 450])
    with pytest.raises(ConfigError, match="360"):
        Roadmap(lab, [360])
    with pytest.raises(ConfigError, match="w1"):
        Roadmap(lab, [90], w1=0.0)
    with pytest.raises(ConfigError, match="w1"):
        Roadmap(lab, [90], w1=2.0, w2=1.0)
    with pytest.raises(ConfigError, match="cell number"):
        Roadmap(lab, [90]).plan(384, 0)


# -- single queries ---------------------------------------------------------------------------

def test_small_plan_in_the_empty_rectangle():
    """Derived case: empty 5×4, Φ = {90°}, (0,0,E) → (4,3,W): ``0 0 0 0 90 0 0 0 90``,
    weight 9: four steps East, turn North at the wall, three steps up, turn West."""
    model = rect(5, 4)
    rm = Roadmap(model, [90])
    plan = rm.plan(cell(model, 0, 0, E), cell(model, 4, 3, W))
    assert list(plan.symbols) == [0, 0, 0, 0, 90, 0, 0, 0, 90]
    assert (plan.weight, plan.ticks, plan.angle_changes) == (9.0, 9, 0)
    assert str(plan) == "0000 90 000 90"
    assert plan.cells[4] == cell(model, 4, 0, E) and plan.cells[5] == cell(model, 4, 0, N)


def test_e1_reconstruction_plans(lab):
    """Sec. V-A (plans ỹ1, ỹ2) on ``lab_navigation`` (the 14×7 reconstruction), Φ = {45°, 90°,
    135°}, w1 = 1, w2 = 100, paper ids 1-based:

    * plan(104 → 9) is exactly ỹ2 = ``000000 135 135 000000 135 135 000000 90``, weight 122
      (23 ticks + one change to 90° at w2);
    * plan(9 → 1) is ``90 000000 90 0000000000000 90 000000 90``, weight 29: the printed ỹ1
      drops the leading 90° — facing East in the bottom-right corner the first event must be a
      bump (A10).
    """
    rm = Roadmap(lab, PHI, w1=1, w2=100)
    y2 = rm.plan(104 - 1, 9 - 1)
    assert str(y2) == "000000 135 135 000000 135 135 000000 90"
    assert (y2.weight, y2.ticks, y2.angle_changes) == (122.0, 23, 1)
    assert y2.distinct_angles == {90, 135}
    y1 = rm.plan(9 - 1, 1 - 1)
    assert str(y1) == "90 000000 90 0000000000000 90 000000 90"
    assert (y1.weight, y1.ticks, y1.angle_changes) == (29.0, 29, 0)
    assert y1.distinct_angles == {90}
    assert y1.cells[0] == 8 and y1.cells[-1] == 0 and y2.cells[-1] == 8
    # the all-pairs plans are the same strings
    assert str(rm.plan_between(103, 8)) == str(y2) and rm.all_pairs().L[103, 8] == 122
    assert str(rm.plan_between(8, 0)) == str(y1) and rm.all_pairs().L[8, 0] == 29


def test_first_angle_is_free_and_weights_are_lexicographic(lab):
    """A2: the first bump never pays w2 (every query starts in all layers at cost 0); the
    weight is w1·ticks + (w2 − w1)·changes; a huge w2 minimises changes first."""
    rm = Roadmap(lab, PHI)
    big = Roadmap(lab, PHI, w1=1, w2=10_000)
    rng = np.random.default_rng(1)
    seen = 0
    for i, j in rng.integers(lab.n_cells, size=(300, 2)).tolist():
        plan, other = rm.plan(i, j), big.plan(i, j)
        assert (plan is None) == (other is None)
        if plan is None or i == j:
            continue
        seen += 1
        assert plan.weight == plan.ticks + 99 * plan.angle_changes
        assert other.angle_changes <= plan.angle_changes
        if other.angle_changes == plan.angle_changes:
            assert other.ticks == plan.ticks
        bumps = plan.bumps
        assert plan.angle_changes == sum(a != b for a, b in zip(bumps[:-1], bumps[1:], strict=True))
    assert seen > 50


def test_goal_region_query(lab):
    """A collection of goal cells ends the plan at the cheapest of them."""
    rm = Roadmap(lab, PHI)
    goals = [0, 8, 50]
    plan = rm.plan(103, goals)
    best = min((p for p in (rm.plan(103, g) for g in goals) if p), key=lambda p: p.weight)
    assert plan.weight == best.weight and plan.goal in goals
    assert rm.plan(5, [7, 5]).ticks == 0


# -- all plans --------------------------------------------------------------------------------

def replay(model: CellModel, plan, phi_deg) -> int:
    """Step the deterministic cell model along the plan's symbols; check every symbol."""
    succ = {phi: model.successor(math.radians(phi)) for phi in phi_deg}
    any_succ, any_bump = succ[phi_deg[0]]
    z = plan.start
    for symbol, expected in zip(plan.symbols, plan.cells[1:], strict=True):
        if symbol == 0:
            assert not any_bump[z], "a 0 where the move is blocked"
            z = int(any_succ[z])
        else:
            nxt, bump = succ[symbol]
            assert bump[z], "an angle where the move is free"
            z = int(nxt[z])
        assert z == expected
    return z


def test_all_plans_replay_on_the_cell_model(small):
    """Alg. 2 (Sec. IV-B): every M[i][j] replayed on the deterministic cell model from i
    ends at j; a 0 only where the move is unblocked, an angle only where blocked;
    L[i][j] = −1 ⇔ M[i][j] = None; L[i][i] = 0; L equals the weight recomputed from the
    string (w1 per tick, w2 − w1 more per change of angle)."""
    model, rm, ap = small
    n = model.n_cells
    assert ap.L.shape == (n, n)
    np.testing.assert_array_equal(np.diag(ap.L), 0)
    assert np.all((ap.L == -1) | (ap.L >= 0))
    reachable = 0
    for i in range(n):
        for j in range(n):
            plan = ap.plan_between(i, j)
            assert (plan is None) == (ap.L[i, j] == -1)
            if plan is None:
                continue
            reachable += 1
            assert replay(model, plan, PHI) == j
            bumps = plan.bumps
            changes = sum(a != b for a, b in zip(bumps[:-1], bumps[1:], strict=True))
            assert ap.L[i, j] == plan.ticks + 99 * changes == plan.weight
    assert n < reachable < n * n  # some pairs have no plan (Sec. V-B), most do


def test_all_pairs_match_an_independent_networkx_roadmap(small):
    """Alg. 1 (Sec. IV-A): the weights equal a brute-force Dijkstra on a layered graph built
    separately with networkx from `CellModel.successor`; unreachable pairs (L = −1) are exactly
    the pairs with no path in it; single queries agree with the all-pairs result."""
    model, rm, ap = small
    n = model.n_cells
    succ = [model.successor(math.radians(phi)) for phi in PHI]
    graph = nx.DiGraph()
    for z in range(n):
        for i in range(len(PHI)):
            if not succ[0][1][z]:
                graph.add_edge((z, i), (int(succ[0][0][z]), i), weight=1)
            else:
                for k in range(len(PHI)):
                    graph.add_edge((z, i), (int(succ[k][0][z]), k), weight=1 if k == i else 100)
    for s in range(n):
        dist = nx.multi_source_dijkstra_path_length(graph, {(s, i) for i in range(len(PHI))})
        reach = set().union(*(nx.descendants(graph, (s, i)) | {(s, i)} for i in range(3)))
        expected = np.array([min((dist[(g, i)] for i in range(3) if (g, i) in dist),
                                 default=-1) for g in range(n)], dtype=float)
        expected[s] = 0
        np.testing.assert_array_equal(ap.L[s], expected)
        np.testing.assert_array_equal(
            ap.L[s] >= 0, [any((g, i) in reach for i in range(3)) for g in range(n)])
    rng = np.random.default_rng(3)
    for i, j in rng.integers(n, size=(100, 2)).tolist():
        plan = rm.plan(i, j)
        assert (plan is None and ap.L[i, j] == -1) or plan.weight == ap.L[i, j]


def test_all_pairs_runs_exactly_n_dijkstras(monkeypatch, lab):
    """Alg. 2 on the layered graph (docs/choices/navigation_coverage.md, "The roadmap remembers the current bounce
    angle") makes exactly N single-source Dijkstra calls (one per
    start cell, all its layers as sources), not N² pair queries."""
    calls = []
    real = roadmap.dijkstra

    def counting(*args, **kwargs):
        calls.append(np.atleast_1d(kwargs["indices"]).tolist())
        return real(*args, **kwargs)

    monkeypatch.setattr(roadmap, "dijkstra", counting)
    rm = Roadmap(lab, PHI)
    rm.all_pairs()
    assert len(calls) == lab.n_cells == rm.dijkstra_calls
    assert calls[7] == [7, 7 + 384, 7 + 768]
    rm.plan_between(3, 200)  # decoded from the stored trees, no new search
    assert len(calls) == lab.n_cells


def test_distinct_angle_counts_match_the_decoded_plans(small):
    """The Fig. 7 statistic from the predecessor trees equals the decoded plans' angle sets."""
    model, _, ap = small
    counts = ap.distinct_angle_counts()
    masks = ap.angle_masks()
    for i in range(0, model.n_cells, 7):
        for j in range(model.n_cells):
            plan = ap.plan_between(i, j)
            if plan is None:
                assert counts[i, j] == -1
                continue
            assert counts[i, j] == len(plan.distinct_angles)
            assert masks[i, j] == sum(1 << PHI.index(a) for a in plan.distinct_angles)
    hist = ap.histogram()
    assert sum(hist.values()) == model.n_cells * (model.n_cells - 1)
    assert hist["none"] == int(np.sum(ap.L < 0))


def test_all_pairs_with_few_kept_trees_gives_the_same_plans(small):
    """With a tree budget of one predecessor tree, the weights, plans and angle statistics equal
    those of the run that keeps every tree; a start whose tree was dropped is searched again
    (and kept, least recently used first out). L is float32 when that is exact."""
    model, _, full = small
    rm = Roadmap(model, PHI)
    ap = rm.all_pairs(tree_budget=1)
    n = model.n_cells
    assert ap.capacity == 1 and rm.dijkstra_calls == n
    assert full.L.dtype == ap.L.dtype == np.float32
    np.testing.assert_array_equal(ap.L, full.L)
    np.testing.assert_array_equal(ap.end_layer, full.end_layer)
    for i, j in [(0, 5), (0, 9), (17, 3), (n - 1, 2)]:
        assert str(ap.plan_between(i, j)) == str(full.plan_between(i, j))
    # 0, 17 and n - 1 (kept last by all_pairs, dropped for 0) searched again; 0 kept for (0, 9)
    assert rm.dijkstra_calls == n + 3
    np.testing.assert_array_equal(ap.angle_masks(), full.angle_masks())
    np.testing.assert_array_equal(ap.distinct_angle_counts(), full.distinct_angle_counts())
    assert ap.histogram() == full.histogram()


def test_all_pairs_weights_stay_float64_when_float32_is_not_exact():
    """w1 = 0.1 makes sums that float32 cannot hold: L is float64 and equals the single
    queries' weights."""
    model = small_map()
    rm = Roadmap(model, PHI, w1=0.1, w2=10.0)
    ap = rm.all_pairs()
    assert ap.L.dtype == np.float64
    rng = np.random.default_rng(5)
    for i, j in rng.integers(model.n_cells, size=(50, 2)).tolist():
        plan = rm.plan(i, j)
        assert (plan is None and ap.L[i, j] == -1) or plan.weight == ap.L[i, j]


def test_fig7_histogram_on_the_reconstruction(lab):
    """Sec. V-B, Fig. 7: on our lab_navigation reconstruction an independent script found {0: 568,
    1: 36547, 2: 25698, 3: 5770} with 78 489 unreachable ordered pairs. Which angles a plan uses can
    depend on Dijkstra's tie-breaking between equal-weight paths, so only the reachability
    and the 0-angle count are exact; 1 > 2 > 3 (the paper's Fig. 7 has 1 > 3 > 2)."""
    hist = Roadmap(lab, PHI).all_pairs().histogram()
    assert hist["none"] == 78_489 and hist[0] == 568
    assert sum(hist[c] for c in (1, 2, 3)) == 36_547 + 25_698 + 5_770
    assert abs(hist[1] - 36_547) <= 100 and abs(hist[2] - 25_698) <= 100
    assert hist[1] > hist[2] > hist[3] > hist[0]


# -- execution in the env ---------------------------------------------------------------------

def nav_env(world="lab_navigation") -> BounceEnv:
    """The lab on the cell backend with the papers' cost as the reward."""
    return BounceEnv(world=world, backend="cell", task="navigation", angles=list(PHI),
                     task_kwargs={"goal_radius": 0.3, "heading_tolerance_deg": 10,
                                  "reward": "plan_cost"})


def pose(model: CellModel, z: int) -> dict:
    centre, heading = model.configuration(z)
    return {"position": centre.tolist(), "heading": float(heading)}


def run_plan(env: BounceEnv, model: CellModel, plan, policy=None) -> dict:
    """Execute a plan from its start to its goal; what the env reports."""
    obs, info = env.reset(options={"start": pose(model, plan.start),
                                   "goal": pose(model, plan.goal)})
    policy = policy or PlanExecutor(plan)
    policy.reset(env)
    task = env.task
    total, steps, ticks_before, reward, terminated = 0.0, 0, 0, 0.0, False
    for _ in range(len(plan.bumps) + 5):
        action = policy.act(obs, info)
        ticks_before = info["ticks"]
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        steps += 1
        if terminated or truncated:
            break
    # ticks charged in the last step, up to the goal (the step itself drives on to a wall)
    last = (task.goal_bonus * terminated - reward
            - (task.w2 - task.w1) * info["angle_changed"]) / task.w1
    return {"terminated": terminated, "steps": steps, "total": total,
            "ticks_to_goal": ticks_before + last, "policy": policy}


def check_execution(env, model, plan) -> None:
    """The plan reaches the goal in the step of its last bump, after exactly plan.ticks ticks,
    without deviating; the env charges −w1 per tick and −(w2 − w1) per change but nothing for
    the drive of its reset (the plan's leading 0s), so the episode return is
    −(weight − w1·leading zeros) + goal bonus."""
    out = run_plan(env, model, plan)
    assert out["terminated"] and out["steps"] == len(plan.bumps)
    assert not out["policy"].deviated and not out["policy"].exhausted
    assert out["ticks_to_goal"] == plan.ticks
    assert out["total"] == pytest.approx(-(plan.weight - plan.leading_zeros) + 100.0)


def test_e1_plans_execute_in_the_cell_env(lab):
    """ỹ2 and ỹ1 (Sec. V-A) replayed in `BounceEnv` (cell backend, bounce steps): they
    reach the goal with the plan's tick count and return −116 + 100 and −29 + 100."""
    env = nav_env()
    model = env.cell_model()
    rm = Roadmap(model, PHI)
    y2, y1 = rm.plan(103, 8), rm.plan(8, 0)
    check_execution(env, model, y2)
    check_execution(env, model, y1)
    out = run_plan(env, model, y2)
    assert out["total"] == pytest.approx(100 - 116)


def test_sampled_plans_execute_in_the_cell_env(lab):
    """Every plan with at least one bump (a plan without bumps ends inside the env's reset
    drive, which the task does not check) of a seeded sample of lab_navigation pairs executes
    exactly in the env (see `check_execution`)."""
    env = nav_env()
    model = env.cell_model()
    ap = Roadmap(model, PHI).all_pairs()
    rng = np.random.default_rng(0)
    done = 0
    for i, j in rng.integers(model.n_cells, size=(1500, 2)).tolist():
        plan = ap.plan_between(i, j)
        if plan is None or not plan.bumps:
            continue
        check_execution(env, model, plan)
        done += 1
    assert done > 400


def test_executor_flags_a_deviation_and_maps_angles_to_env_indices(lab):
    """The executor's actions are indices into the env's Φ (here in another order); replaying a
    plan from the wrong start makes the clock disagree with the plan's runs of 0s."""
    env = BounceEnv(world="lab_navigation", backend="cell", task="navigation",
                    angles=[135, 90, 45],
                    task_kwargs={"goal_radius": 0.3, "heading_tolerance_deg": 10})
    rm = Roadmap(lab, PHI)
    y2 = rm.plan(103, 8)
    ex = PlanExecutor(y2)
    obs, info = env.reset(options={"start": pose(lab, 103), "goal": pose(lab, 8)})
    ex.reset(env)
    assert [ex.act(obs, info)] == [0]  # 135° is index 0 of this env's Φ
    assert not ex.deviated
    obs, info = env.reset(options={"start": pose(lab, 0), "goal": pose(lab, 8)})
    ex.reset(env)
    ex.act(obs, info)
    assert ex.deviated and ex.deviations == [(0, 6, info["clock"])]
    with pytest.raises(ConfigError, match="not one of the env's angles"):
        PlanExecutor(y2).reset(BounceEnv(world="lab_navigation", backend="cell",
                                         task="navigation", angles=[45, 90]))


def test_navigation_planner_reads_the_episode_and_replans_past_the_reset_drive(lab):
    """`NavigationPlanner` maps the task's start and goal to cells and plans with the task's
    w1, w2: ỹ2 from 104 to 9. A goal straight ahead of the start (plan ``00000``, no bump)
    is passed during the env's reset drive; the planner replans from the cell it tracks on the
    model and still reaches it."""
    env = nav_env()
    model = env.cell_model()
    planner = NavigationPlanner()
    y2 = Roadmap(model, PHI).plan(103, 8)
    out = run_plan(env, model, y2, policy=planner)
    assert str(planner.plan) == str(y2) and planner.start_cell == 103
    assert list(planner.goal_cells) == [8] and planner.replans == 0
    assert out["terminated"] and out["total"] == pytest.approx(-(122 - 6) + 100)

    straight = Roadmap(model, PHI).plan(0, 5)
    assert str(straight) == "00000"
    planner = NavigationPlanner()
    out = run_plan(env, model, straight, policy=planner)
    # the env sees no arrival on its reset drive: the plan is the drive, then a cycle back
    assert out["terminated"] and planner.replans == 0 and planner.plan.bumps
    assert planner.plan.start == 0 and planner.plan.goal == 5
    assert planner.plan.cells[7] == cell(model, 7, 0, E)  # the drive ends at the block
    drive = planner.plan.leading_zeros  # charged at reset, not in the step rewards
    assert drive == 7
    assert out["total"] == pytest.approx(-(planner.plan.weight - drive) + 100)


def test_nonempty_plan_from_a_goal_cell_is_a_cycle(small):
    """``plan(z, z)`` is the empty plan; with ``nonempty`` the cheapest cycle back to z."""
    _, rm, _ = small
    cycles = 0
    for z in np.flatnonzero(rm.blocked)[:5].tolist():
        assert rm.plan(z, z).ticks == 0
        cycle = rm.plan(z, z, nonempty=True)
        if cycle is None:
            continue
        assert cycle.ticks >= 1 and cycle.cells[0] == cycle.cells[-1] == z
        assert cycle.weight == pytest.approx(rm.w1 * cycle.ticks
                                             + (rm.w2 - rm.w1) * cycle.angle_changes)
        cycles += 1
    assert cycles


#: the L-shaped room of examples/planners_on_custom_map.py
L_ROOM = [(0, 0), (12, 0), (12, 5), (6, 5), (6, 10), (0, 10)]
L_PILLAR = [(2, 2), (4, 2), (4, 4), (2, 4)]


@pytest.fixture(scope="module")
def l_room_env(tmp_path_factory):
    import gymnasium as gym

    import bounce_gym  # noqa: F401  (registers the environments)
    from bounce_gym import worlds
    from bounce_gym.worlds import World

    path = worlds.save(World(L_ROOM, [L_PILLAR], name="l_room"),
                       tmp_path_factory.mktemp("l_room") / "l_room.yaml")
    env = gym.make("bounce_gym/BounceNavigation-v0", world=str(path), backend="cell")
    yield env
    env.close()


def run_planner(env, seed: int) -> tuple[NavigationPlanner, dict]:
    obs, info = env.reset(seed=seed)
    planner = NavigationPlanner()
    planner.reset(env)
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(planner.act(obs, info))
        done = terminated or truncated
    return planner, info


@pytest.mark.parametrize("seed", [10045, 10084])
def test_l_room_plans_ending_on_the_goal_circle_arrive(l_room_env, seed):
    """The examples' L-shaped room: these plans end in a cell whose centre lies exactly
    goal_radius from the goal point (a goal cell); the env's arrival test computed the drive's
    entry into the closed goal disk one ulp past the drive's end and missed it."""
    planner, info = run_planner(l_room_env, seed)
    assert planner.plan is not None and planner.replans == 0
    assert info["is_success"] and info["plan_cost"] == planner.predicted_weight


def test_l_room_start_equal_to_goal_is_not_feasible_in_bounce_mode(l_room_env):
    """Seed 10094 draws start = goal (the empty plan); the reset drive leaves the goal region,
    the env never tests the start, and no plan enters the region again (its cells head 45°
    along diagonals from the west wall, where no bump turns to 45°). The pair is infeasible in
    the env, and the planner and the feasibility check say so."""
    from bounce_gym_experiments.families.navigation import Feasibility

    planner, info = run_planner(l_room_env, 10094)
    assert planner.start_cell in planner.goal_cells.tolist()
    assert planner.roadmap.plan(planner.start_cell, planner.goal_cells).ticks == 0
    assert planner.plan is None and not info["is_success"]
    assert not Feasibility()(l_room_env)


def test_goal_cells_cover_the_task_goal_region(lab):
    """The goal region (disk + heading tolerance) as cells; the single cell without one."""
    z = cell(lab, 3, 0, N)
    np.testing.assert_array_equal(goal_cells(lab, [3.5, 0.5], math.pi / 2, 0.3, math.radians(10)),
                                  [z])
    region = goal_cells(lab, [3.9, 0.5], math.pi / 2 + 0.1, 1.0, math.radians(22.5))
    assert set(region.tolist()) == {cell(lab, 3, 0, N), cell(lab, 4, 0, N)}
    np.testing.assert_array_equal(goal_cells(lab, [3.5, 0.5], math.pi / 2), [z])
    assert len(goal_cells(lab, [3.5, 3.5], 0.0)) == 0  # inside the obstacle
