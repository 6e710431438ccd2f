"""The joint cell map and multi-robot coverage (Alam & Bobadilla 2020, §3.2 and §4.1:
Eq. 6, Algorithm 1; choices where the article is open: docs/choices/multirobot.md)."""

import math

import numpy as np
import pytest

from baselines.multirobot import plan_coverage, random_start
from bounce_gym import worlds
from bounce_gym.cells import CellModel, JointCellModel, resolve_moves, too_close
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError


def _model(rows, rule="target_only"):
    return CellModel(worlds.world_from_grid(worlds.parse_ascii(rows)), corner_rule=rule)


def _cell(model, row, col, deg):
    return int(model.cell_id(model.position_index[row, col], round(deg / 45) % 8))


def _pose(model, z):
    p, k = model.decode(np.asarray(z))
    return model.position_rc[p], k * 45


@pytest.fixture(scope="module")
def grid10():
    return CellModel(worlds.get("grid_10x10"), corner_rule="no_squeeze")


def test_eq6_moves_and_blocked_rotation():
    model = _model(["....", "....", "...."])  # rows: top first; row index 0 = bottom
    jm = JointCellModel(model, [135, 135])
    x = np.array([_cell(model, 0, 0, 0), _cell(model, 1, 2, 45)])
    rc, deg = _pose(model, jm.step(x))
    assert rc.tolist() == [[0, 1], [2, 3]] and deg.tolist() == [0, 45]  # (+1, 0) and (+1, +1)
    x = np.array([_cell(model, 0, 3, 0), _cell(model, 2, 0, 90)])  # both face the boundary
    rc, deg = _pose(model, jm.step(x))
    assert rc.tolist() == [[0, 3], [2, 0]] and deg.tolist() == [135, 225]  # stay, CCW by φ


def test_head_on_corridor_both_turn_and_never_share_or_swap():
    model = _model(["....."])  # a 1 x 5 corridor
    jm = JointCellModel(model, [135, 135])
    for gap in (2, 3):  # meet with an odd gap (same target) or even gap (swap)
        x = np.array([_cell(model, 0, 0, 0), _cell(model, 0, gap, 180)])
        for _ in range(gap):
            p0 = x % model.n_positions
            nxt, pairs = jm.step(x, return_collisions=True)
            p1 = nxt % model.n_positions
            assert p1[0] != p1[1] and not (p1[0] == p0[1] and p1[1] == p0[0])
            if pairs:
                _, deg = _pose(model, nxt)
                assert deg.tolist() == [135, 315] and np.array_equal(p0, p1)
                break
            x = nxt
        else:
            pytest.fail("the robots never collided")


def test_no_two_robots_share_or_swap(grid10):
    jm = JointCellModel(grid10, [135] * 5)
    x = jm.random_joint(np.random.default_rng(0), 64)
    for _ in range(300):
        nxt = jm.step(x)
        assert jm.valid(nxt).all()
        p0, p1 = x % grid10.n_positions, nxt % grid10.n_positions
        swap = (p1[:, :, None] == p0[:, None, :]) & (p1[:, None, :] == p0[:, :, None])
        swap &= ~np.eye(5, dtype=bool)
        assert not swap.any()
        x = nxt


@pytest.mark.parametrize("phi", [45, 90, 135])
def test_one_robot_is_the_scm(grid10, phi):
    jm = JointCellModel(grid10, [phi])
    succ, _ = grid10.successor(math.radians(phi))
    z = np.arange(grid10.n_cells)
    assert np.array_equal(jm.step(z[:, None])[:, 0], succ)
    res = plan_coverage(jm, [int(z[17])], max_steps=50)
    first = res.edge_kinds.index("jump") if "jump" in res.edge_kinds else len(res.edge_kinds)
    orbit = [17]
    for _ in range(first):
        orbit.append(int(succ[orbit[-1]]))
    assert [int(t[0]) for t in res.trajectory[:first + 1]] == orbit


def test_independent_robots_product_structure(grid10):
    succ, _ = grid10.successor(math.radians(135))
    jm = JointCellModel(grid10, [135, 135], collisions=False)

    def periodic(z):
        for _ in range(grid10.n_cells):
            z = int(succ[z])
        n, w = 1, int(succ[z])
        while w != z:
            n, w = n + 1, int(succ[w])
        return z, n

    rng = np.random.default_rng(1)
    for _ in range(5):
        (a, pa), (b, pb) = periodic(int(rng.integers(grid10.n_cells))), \
            periodic(int(rng.integers(grid10.n_cells)))
        x0 = np.array([a, b])
        x, k = jm.step(x0), 1
        while not np.array_equal(x, x0):
            x, k = jm.step(x), k + 1
        assert k == math.lcm(pa, pb)
    # the pa·pb joint cells of two cycles form gcd(pa, pb) groups of period lcm(pa, pb)
    ca, cb = [a], [b]
    while len(ca) < pa:
        ca.append(int(succ[ca[-1]]))
    while len(cb) < pb:
        cb.append(int(succ[cb[-1]]))
    todo = {(u, v) for u in ca for v in cb}
    groups = 0
    while todo:
        x = np.array(todo.pop())
        groups += 1
        for _ in range(math.lcm(pa, pb) - 1):
            x = jm.step(x)
            todo.remove(tuple(int(v) for v in x))
    assert groups == math.gcd(pa, pb)


def test_encode_decode_and_neighbours(grid10):
    jm = JointCellModel(grid10, [135] * 3)
    x = jm.random_joint(np.random.default_rng(2), 50)
    assert np.array_equal(jm.decode(jm.encode(x)), x)
    assert jm.index_of(x[0]) == int(jm.encode(x[0]))
    for mode, cap in (("rotation", 6), ("full", 18)):
        nb = jm.neighbors(x[0], mode)
        assert 0 < len(nb) <= cap and jm.valid(nb).all()
    rot = jm.neighbors(x[0], "rotation")
    assert len(rot) == 6 and np.array_equal(rot % grid10.n_positions,
                                            np.broadcast_to(x[0] % grid10.n_positions, (6, 3)))


@pytest.mark.parametrize("m", [2, 3, 5, 12])
def test_joint_map_agrees_with_the_env_cell_backend(m):
    for seed in range(2):
        env = MultiBounceEnv(world="grid_10x10", n_robots=m, backend="cell", robot_radius=0.0,
                             angles=[135], step_mode="tick", robot_collisions="bounce")
        env.reset(seed=seed)
        backend, state = env.core.dynamics.backend, env.core.state
        jm = JointCellModel(backend.model, [135] * m)
        x = backend.cells(state)
        for _ in range(300):
            x = jm.step(x)
            env.step(dict.fromkeys(env.agents, 0))
            assert np.array_equal(x, backend.cells(state))
            assert np.allclose(state.position, backend.model.centres[x % backend.model.n_positions])
        env.close()


def _check_structure(jm, res, x0):
    model = jm.model
    assert np.array_equal(res.trajectory[0], x0)
    assert len(res.edge_kinds) == len(res.trajectory) - 1
    for t, kind in enumerate(res.edge_kinds):
        a, b = res.trajectory[t], res.trajectory[t + 1]
        if kind == "step":
            assert np.array_equal(jm.step(a), b)
        else:
            assert kind == "jump"
            pa, ka = model.decode(a)
            pb, kb = model.decode(b)
            assert np.array_equal(pa, pb)
            d = (kb - ka) % model.n_bins
            assert np.count_nonzero(d) == 1 and d[d != 0][0] in (1, model.n_bins - 1)
            assert t in res.jumps


def test_coverage_structure_on_an_empty_rectangle():
    model = _model(["......"] * 5, rule="no_squeeze")
    jm = JointCellModel(model, [135, 135])
    x0 = np.array([_cell(model, 0, 0, 0), _cell(model, 4, 5, 180)])
    res = plan_coverage(jm, x0)
    _check_structure(jm, res, x0)
    assert res.steps_to_full is not None and res.coverage[res.steps_to_full] == 1.0
    assert res.checkpoint_length >= res.steps_to_full


@pytest.mark.parametrize("m", [2, 3, 4, 5])
def test_full_coverage_on_grid_10x10(grid10, m):
    steps = []
    for seed in range(3):
        jm = JointCellModel(grid10, [135] * m)
        x0 = random_start(jm, seed)
        res = plan_coverage(jm, x0, stop_at_full=True)
        _check_structure(jm, res, x0)
        assert res.steps_to_full is not None and res.final_coverage == 1.0
        assert res.n_reachable == grid10.n_positions
        steps.append(res.steps_to_full)
    print(f"grid_10x10 m={m}: steps to full coverage {steps}")


def test_full_neighbourhood_jumps_change_one_robot_by_one_unit(grid10):
    jm = JointCellModel(grid10, [135, 135])
    res = plan_coverage(jm, random_start(jm, 0), neighbors="full", stop_at_full=True)
    assert res.steps_to_full is not None
    for t in res.jumps:
        a, b = res.trajectory[t], res.trajectory[t + 1]
        assert np.count_nonzero(a != b) == 1 and jm.valid(b).all()


def test_trend_more_robots_cover_grid_10x10_faster(grid10):
    """§5.1, Fig. 7b (layouts unpublished): 20 seeds, φ = 135°, mean steps
    to full coverage with m = 2 exceed those with m = 5 and are of the order of 10³."""
    mean = {}
    for m in (2, 5):
        jm = JointCellModel(grid10, [135] * m)
        steps = [plan_coverage(jm, random_start(jm, s), max_steps=30_000,
                               stop_at_full=True).steps_to_full for s in range(20)]
        assert None not in steps
        mean[m] = float(np.mean(steps))
    assert mean[2] > mean[5]
    assert 10 ** 2.5 < mean[2] < 10 ** 3.5


def test_ten_robots_cover_grid_20x12():
    """§5.1, Fig. 9 (98 %): m = 10, φ = 135° reach ≥ 95 % coverage."""
    model = CellModel(worlds.get("grid_20x12"), corner_rule="no_squeeze")
    jm = JointCellModel(model, [135] * 10)
    for seed in range(3):
        res = plan_coverage(jm, random_start(jm, seed), max_steps=5000, stop_at_full=True)
        assert res.final_coverage >= 0.95


@pytest.mark.parametrize("phi, size", [(45, 8), (135, 8), (90, 4), (180, 2)])
def test_orientation_orbit_sizes(phi, size):
    """Derived case: a robot that can never move (a one-cell world) only rotates by φ; its
    orbit over the 8 headings has 8 / gcd(φ/45°, 8) cells."""
    model = _model(["."])
    jm = JointCellModel(model, [phi])
    z = np.array([_cell(model, 0, 0, 0)])
    seen = []
    while int(z[0]) not in seen:
        seen.append(int(z[0]))
        z = jm.step(z)
    assert len(seen) == size and int(z[0]) == seen[0]


def test_min_sep_zero_is_the_same_cell_rule(grid10):
    jm0, jm = JointCellModel(grid10, [135] * 5), JointCellModel(grid10, [135] * 5, min_sep_cells=0)
    x = jm0.random_joint(np.random.default_rng(1), 64)
    assert jm.close is None
    p, k = grid10.decode(x)
    target = grid10.targets[k, p]
    plain = resolve_moves(p, target, grid10.position_rc)
    explicit = resolve_moves(p, target, grid10.position_rc, too_close(grid10.position_rc, 0))
    for a, b in zip(plain, explicit, strict=True):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("sep", [1, 2])
def test_min_sep_cells_keeps_robots_apart(grid10, sep):
    """docs/choices/multirobot.md, "Robot–robot conflicts on the grid", option: robots never come within
    Chebyshev distance min_sep_cells."""
    jm = JointCellModel(grid10, [135] * 4, min_sep_cells=sep)
    x = jm.random_joint(np.random.default_rng(0), 32)
    rc = grid10.position_rc
    for _ in range(200):
        x = jm.step(x)
        assert jm.valid(x).all()
        pos = rc[x % grid10.n_positions]  # (32, 4, 2)
        cheb = np.abs(pos[:, :, None] - pos[:, None, :]).max(axis=3) + 100 * np.eye(4, dtype=int)
        assert cheb.min() > sep


def test_min_sep_cells_in_the_env_agrees_with_the_joint_map():
    env = MultiBounceEnv(world="grid_10x10", n_robots=4, backend="cell", angles=[135],
                         step_mode="tick", robot_collisions="bounce", min_sep_cells=1)
    env.reset(seed=3)
    backend, state = env.core.dynamics.backend, env.core.state
    jm = JointCellModel(backend.model, [135] * 4, min_sep_cells=1)
    x = backend.cells(state)
    assert jm.valid(x)[0]
    for _ in range(300):
        x = jm.step(x)
        env.step(dict.fromkeys(env.agents, 0))
        assert np.array_equal(x, backend.cells(state))


@pytest.mark.parametrize("kwargs, message", [
    (dict(min_sep_cells=1, backend="kinematic", robot_radius=0.3), "only the cell backend"),
    (dict(min_sep_cells=-1), "min_sep_cells: expected an integer >= 0, got -1"),
    (dict(min_sep_cells=1.5), "min_sep_cells: expected an integer >= 0, got 1.5"),
])
def test_min_sep_cells_bad_arguments(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        MultiBounceEnv(**{"world": "grid_10x10", "n_robots": 2, "backend": "cell", **kwargs})


def test_min_sep_cells_rejects_close_starts():
    env = MultiBounceEnv(world="grid_10x10", n_robots=2, backend="cell", min_sep_cells=1)
    with pytest.raises(ConfigError, match="within min_sep_cells"):
        env.reset(options={"start": {"position": [[0.5, 0.5], [1.5, 1.5]], "heading": [0, 0]}})
