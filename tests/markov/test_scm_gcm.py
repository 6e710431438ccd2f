"""Simple and generalized cell mapping analyses (issue #4): `bounce_gym.markov.scm`, `bounce_gym.markov.gcm`.

Sources: Alam, Bobadilla & Shell 2018, Sec. III-B and IV-A (Defs. 1-4, Algorithm 1); Alam, Bobadilla
& Shell 2017, Sec. III-B and IV-C (GCM, Alg. 3); thesis Defs. 2.3.1-2.3.4, §3.3.3 and §5.4 (GCM
groups and domiciles); choices where the papers are open: docs/choices/index.md.
Coordinates are (column, row) with the origin bottom-left; bins count counter-clockwise from East.
"""

from __future__ import annotations

import math
import tracemalloc

import networkx as nx
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from bounce_gym.cells import CellModel
from bounce_gym.errors import ConfigError
from bounce_gym.markov.gcm import MODES, gcm, generalized_cell_mapping
from bounce_gym.markov.scm import scm, simple_cell_mapping
from bounce_gym.worlds import get, random_grid, world_from_grid

DEG = math.pi / 180


# -- helpers ----------------------------------------------------------------------------------
def rect(width: int, height: int, n_bins: int) -> CellModel:
    return CellModel(world_from_grid(np.ones((height, width), dtype=bool)), n_bins=n_bins)


def cell(model: CellModel, col: int, row: int, k: int) -> int:
    return int(model.cell_id(model.position_index[row, col], k))


def algorithm1(succ: np.ndarray, order) -> tuple[np.ndarray, np.ndarray, int]:
    """The paper's sequential MODIFIEDSIMPLECELLMAPPING with its index errors fixed
    (docs/choices/cell_model.md, "Algorithm 1's index errors and order independence")
    (separate cursor, d = first index of z in the walk, line 27 into T_{g_z}), visiting the cells
    in ``order``. Returns (group 0-based, s, r)."""
    n = len(succ)
    g = np.zeros(n, dtype=np.int64)
    s = np.full(n, -1, dtype=np.int64)
    r = 0
    for i in order:
        if g[i] != 0:
            continue
        walk, z = [], int(i)
        while g[z] == 0:
            g[z] = -1
            walk.append(z)
            z = int(succ[z])
        k = len(walk)
        if g[z] == -1:  # the cycle closed inside this walk, at index d
            r += 1
            d = walk.index(z)
            for j in range(k):
                g[walk[j]] = r
                s[walk[j]] = d - j if j < d else 0
        else:  # ran into a classified cell
            for j in range(k):
                g[walk[j]] = g[z]
                s[walk[j]] = s[z] + k - j
    return g - 1, s, r


def same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    """Labels a and b induce the same partition of the cells."""
    pairs = np.unique(np.column_stack((a, b)), axis=0)
    return len(pairs) == len(np.unique(a)) == len(np.unique(b))


def functional_graph(succ: np.ndarray) -> nx.DiGraph:
    graph = nx.DiGraph()
    graph.add_nodes_from(range(len(succ)))
    graph.add_edges_from(enumerate(succ.tolist()))
    return graph


def check_scm_invariants(res, succ: np.ndarray) -> None:
    """The SCM sanity properties (Defs. 1-4, Algorithm 1) on any functional graph."""
    n = len(succ)
    z = np.arange(n)
    assert res.n_cells == n and res.group.shape == res.steps.shape == res.periodic.shape == (n,)
    # the periodic sets P_j and transient sets T_j partition Z
    assert res.group.min() == 0 and res.group.max() == res.n_groups - 1
    sizes = [len(res.basin(g)) for g in range(res.n_groups)]
    assert sum(sizes) == n and min(sizes) >= 1
    on_cycles = np.concatenate(res.cycles)
    assert len(np.unique(on_cycles)) == len(on_cycles) == int(res.periodic.sum())
    assert np.array_equal(np.sort(on_cycles), np.flatnonzero(res.periodic))
    for g in range(res.n_groups):
        assert np.array_equal(np.sort(np.concatenate((res.cycles[g], res.transient_trajectory(g)))),
                              res.basin(g))
    # s = 0 <=> periodic; s_{c(z)} = s_z - 1 for transient z; groups are closed under C
    assert np.array_equal(res.steps == 0, res.periodic)
    tr = np.flatnonzero(~res.periodic)
    assert np.array_equal(res.steps[succ[tr]], res.steps[tr] - 1)
    assert np.array_equal(res.group[succ], res.group)
    assert res.max_transient == res.steps.max()
    # cycles: in the order of C, from their smallest cell, groups numbered by that cell
    assert np.array_equal(res.periods, [len(c) for c in res.cycles])
    for g, cyc in enumerate(res.cycles):
        assert cyc[0] == cyc.min()
        assert np.array_equal(succ[cyc], np.roll(cyc, -1))
        assert np.all(res.group[cyc] == g)
    firsts = [c[0] for c in res.cycles]
    assert firsts == sorted(firsts)
    # C^K(z) = z with K the period of z's group, and K is minimal (cycle cells are distinct)
    pc = np.flatnonzero(res.periodic)
    k = res.period_of(pc)
    image = pc.copy()
    for step in range(1, int(k.max()) + 1):
        image = np.where(step <= k, succ[image], image)
        assert np.array_equal(image == pc, step >= k)
    # C^s(z) is periodic and C^(s-1)(z) is not
    image, before = z.copy(), z.copy()
    for step in range(res.max_transient):
        before = np.where(step < res.steps - 1, succ[before], before)
        image = np.where(step < res.steps, succ[image], image)
    assert res.periodic[image].all()
    assert not res.periodic[before[res.steps > 0]].any()


def check_against_networkx(res, succ: np.ndarray) -> None:
    graph = functional_graph(succ)
    assert res.n_groups == nx.number_weakly_connected_components(graph)
    assert {frozenset(c.tolist()) for c in res.cycles} == {
        frozenset(c) for c in nx.attracting_components(graph)}
    wcc = np.empty(len(succ), dtype=np.int64)
    for i, comp in enumerate(nx.weakly_connected_components(graph)):
        wcc[list(comp)] = i
    assert same_partition(wcc, res.group)


def check_against_algorithm1(res, succ: np.ndarray, rng: np.random.Generator) -> None:
    for order in (range(len(succ)), range(len(succ) - 1, -1, -1), rng.permutation(len(succ))):
        g, s, r = algorithm1(succ, order)
        assert r == res.n_groups
        assert np.array_equal(s, res.steps)
        assert same_partition(g, res.group)


# -- SCM ----------------------------------------------------------------------------------------
@pytest.mark.parametrize(("seed", "n_bins", "phi_deg"),
                         [(0, 4, 90), (1, 4, 270), (2, 8, 45), (3, 8, 135), (4, 8, 90),
                          (5, 8, 225), (6, 12, 150)])
def test_scm_sanity_on_random_grid_worlds(seed, n_bins, phi_deg):
    """Eq. 4 and BUILD-STATEGRAPH: one successor per cell and no self-map; label 0 <=> same bin
    and a position change, label 1 <=> same position and θ+ϕ; P/T partition Z; s=0 <=> periodic;
    s_{c(z)} = s_z - 1; C^K(z) = z (K minimal); r = networkx's number of weakly connected
    components; the periodic sets = nx.attracting_components; s and the groups equal those of the
    paper's Algorithm 1 (errata fixed) for any cell iteration order."""
    rng = np.random.default_rng(seed)
    world = random_grid(rng, int(rng.integers(5, 10)), int(rng.integers(5, 12)), 3, 2)
    model = CellModel(world, n_bins=n_bins)
    res = scm(model, phi_deg * DEG)
    succ = res.successor
    n = model.n_cells
    assert succ.shape == (n,) and succ.min() >= 0 and succ.max() < n
    assert not np.any(succ == np.arange(n))  # no self-map
    p, k = model.decode(np.arange(n))
    p2, k2 = model.decode(succ)
    assert np.array_equal(res.bump, k2 != k)
    assert np.all(p2[~res.bump] != p[~res.bump])
    assert np.all(p2[res.bump] == p[res.bump])
    assert np.all(k2[res.bump] == (k[res.bump] + round(phi_deg * n_bins / 360)) % n_bins)
    check_scm_invariants(res, succ)
    check_against_networkx(res, succ)
    check_against_algorithm1(res, succ, rng)


@pytest.mark.parametrize("seed", range(4))
def test_scm_on_random_functional_graphs(seed):
    """The same properties on arbitrary maps (fixed points and long chains allowed): the
    definitions of periodic cell (period 1 included), transient cell and periodic group (Defs. 1-4),
    cross-checked with networkx and with Algorithm 1."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(50, 400))
    # few targets give many cycles and deep in-trees; the rest random
    succ = rng.integers(0, n, n)
    if seed % 2:
        succ = rng.integers(0, max(2, n // 20), n)
    res = simple_cell_mapping(succ)
    assert res.bump is None
    check_scm_invariants(res, succ)
    check_against_networkx(res, succ)
    check_against_algorithm1(res, succ, rng)


@pytest.mark.parametrize("seed", range(3))
def test_scm_invariant_to_cell_relabelling(seed):
    """docs/choices/cell_model.md, "Algorithm 1's index errors and order independence": results must not depend
    on the cell iteration order. Relabelling the cells by a permutation σ (C' = σ C σ^-1) permutes
    periodic flags, steps, periods and groups alike."""
    rng = np.random.default_rng(10 + seed)
    model = CellModel(random_grid(rng, 8, 9, 3, 3), n_bins=8)
    succ = model.successor([45, 90, 135][seed] * DEG)[0]
    sigma = rng.permutation(len(succ))
    relabelled = np.empty_like(succ)
    relabelled[sigma] = sigma[succ]
    a, b = simple_cell_mapping(succ), simple_cell_mapping(relabelled)
    assert a.n_groups == b.n_groups and a.max_transient == b.max_transient
    assert np.array_equal(b.periodic[sigma], a.periodic)
    assert np.array_equal(b.steps[sigma], a.steps)
    assert np.array_equal(b.period_of(sigma), a.period_of(np.arange(len(succ))))
    assert same_partition(a.group, b.group[sigma])
    assert {frozenset(sigma[c].tolist()) for c in a.cycles} == {
        frozenset(c.tolist()) for c in b.cycles}


def test_scm_long_chain_is_vectorised():
    """Scale (the 9 M cells of Sec. V-A need whole-array code): a 300 000-cell chain into a 7-cycle
    has s up to 300 000; pointer doubling finds every s exactly (a per-level loop would be too slow
    for the test budget)."""
    n_chain, period = 300_000, 7
    n = n_chain + period
    succ = np.arange(1, n + 1)
    succ[-1] = n_chain  # close the cycle
    perm = np.random.default_rng(0).permutation(n)  # scramble the numbering
    scrambled = np.empty_like(succ)
    scrambled[perm] = perm[succ]
    res = simple_cell_mapping(scrambled)
    assert res.n_groups == 1 and res.periods.tolist() == [period]
    expected = np.maximum(n_chain - np.arange(n), 0)
    assert np.array_equal(res.steps[perm], expected)
    assert res.max_transient == n_chain
    assert np.array_equal(np.sort(res.cycles[0]), np.sort(perm[n_chain:]))


@pytest.mark.parametrize("bad", [np.zeros((2, 2), dtype=int), np.array([0.0, 1.0]),
                                 np.array([1, 2]), np.array([-1, 0]), np.array([], dtype=int)])
def test_scm_rejects_bad_successor(bad):
    """A successor array must be a non-empty 1-D integer array of cells (Eq. 2: C maps Z to Z)."""
    with pytest.raises(ConfigError, match="successor"):
        simple_cell_mapping(bad)


@pytest.mark.parametrize(("width", "height"), [(6, 4), (5, 5), (3, 7)])
def test_rectangle_90_is_the_ccw_perimeter_loop(width, height):
    """Analytic case: W×H rectangle, 4 bins, ϕ = 90°: r = 1, the periodic group is the
    CCW perimeter loop of period 2(W+H), observed from (0,0,E) as (0^{W-1} 1 0^{H-1} 1)^2.
    (proto) 6×4: N = 96, N_p = 20, max s = 6."""
    model = rect(width, height, 4)
    res = scm(model, 90 * DEG)
    assert res.n_groups == 1 and res.periods.tolist() == [2 * (width + height)]
    start = cell(model, 0, 0, 0)
    assert res.periodic[start]
    walk = [start]
    for _ in range(2 * (width + height) - 1):
        walk.append(int(res.successor[walk[-1]]))
    assert res.successor[walk[-1]] == start
    labels = "".join("1" if res.bump[z] else "0" for z in walk)
    assert labels == ("0" * (width - 1) + "1" + "0" * (height - 1) + "1") * 2
    rc = model.position_rc[model.decode(np.array(walk))[0]]
    cols, rows = rc[:, 1], rc[:, 0]
    # east along the bottom, north up the right, west along the top, south down the left
    w, h = width, height
    expected_cols = [*range(w), *[w - 1] * h, *range(w - 1, -1, -1), *[0] * h]
    expected_rows = [*[0] * w, *range(h), *[h - 1] * w, *range(h - 1, -1, -1)]
    assert cols.tolist() == expected_cols and rows.tolist() == expected_rows
    if (width, height) == (6, 4):
        assert model.n_cells == 96 and int(res.periodic.sum()) == 20 and res.max_transient == 6


@pytest.mark.parametrize(("width", "height"), [(6, 4), (5, 5)])
def test_rectangle_180_rows_and_columns(width, height):
    """Analytic case: 4 bins, ϕ = 180°: r = W + H, no transient cell; row groups (E/W) have
    period 2W and column groups (N/S) period 2H."""
    model = rect(width, height, 4)
    res = scm(model, 180 * DEG)
    assert res.n_groups == width + height
    assert res.periodic.all() and res.max_transient == 0
    rows = cols = 0
    for cyc in res.cycles:
        p, k = model.decode(cyc)
        rc = model.position_rc[p]
        if set(k.tolist()) == {0, 2}:
            rows += 1
            assert len(cyc) == 2 * width and len(set(rc[:, 0].tolist())) == 1
        else:
            cols += 1
            assert set(k.tolist()) == {1, 3}
            assert len(cyc) == 2 * height and len(set(rc[:, 1].tolist())) == 1
    assert (rows, cols) == (height, width)


def test_symmetry_breaking_room():
    """Symmetry breaking: 8×6 room with obstacle cells {(3,2),(4,2)}, 4 bins, ϕ = 90°: r = 1,
    period 28."""
    free = np.ones((6, 8), dtype=bool)
    free[2, 3] = free[2, 4] = False
    res = scm(CellModel(world_from_grid(free), n_bins=4), 90 * DEG)
    assert res.n_groups == 1 and res.periods.tolist() == [28]


@pytest.mark.parametrize(("phi_deg", "periods"), [(45, [24]), (135, [24, 28, 32, 36])])
def test_eight_bins_empty_6x4(phi_deg, periods):
    """Prototype numbers: empty 6×4, 8 bins: ϕ = 45° gives r = 1 of period 24; ϕ = 135°
    gives r = 4 with periods {24, 28, 32, 36}."""
    res = scm(rect(6, 4, 8), phi_deg * DEG)
    assert res.n_groups == len(periods)
    assert sorted(res.periods.tolist()) == periods


@pytest.mark.parametrize(("name", "phi_deg", "r"), [
    ("lab_localization_a", 45, 1), ("lab_localization_b", 135, 2),
    ("lab_localization_a", 135, 1), ("lab_localization_b", 45, 1)])
def test_lab_localization_maps(name, phi_deg, r):
    """Paper Tables I/II structure on the reconstructed 19-cell lab maps (zoo descriptions; the
    layouts are reconstructions, so only the structure is claimed, docs/choices/cell_model.md): N = 19 x 8 =
    152 cells, an NFA of N + 1 = 153 states; map a has r = 1 at 45°, map b has r = 2 at 135°
    (and the reconstructions give r = 1 at the other angle)."""
    model = CellModel(get(name), n_bins=8)
    assert model.n_positions == 19 and model.n_cells == 152 and model.n_cells + 1 == 153
    res = scm(model, phi_deg * DEG)
    assert res.n_groups == r
    check_scm_invariants(res, res.successor)


@pytest.mark.parametrize(("name", "n_bins", "n_positions", "n_cells"), [
    ("lab_navigation", 8, 48, 384), ("lab_fig1", 8, 54, 432), ("lab_complex", 8, 183, 1464),
    ("lab_complex", 360, 183, 65880), ("lab_localization_a", 8, 19, 152)])
def test_zoo_cell_counts(name, n_bins, n_positions, n_cells):
    """Alam, Bobadilla & Shell 2017, Sec. V / thesis §3.5:
    N = N_pos · n_θ: 384 = 48·8, 432 = 54·8, 1464 = 183·8,
    65880 = 183·360, 152 = 19·8; the SCM covers all N cells."""
    model = CellModel(get(name), n_bins=n_bins)
    assert (model.n_positions, model.n_cells) == (n_positions, n_cells)
    res = scm(model, 90 * DEG)
    assert res.n_cells == n_cells and sum(len(res.basin(g)) for g in range(res.n_groups)) == n_cells


# -- GCM ----------------------------------------------------------------------------------------
def test_boundary_cycle_5x4():
    """Derived case: empty 5×4 rectangle, 8 bins, Φ = {90°}, ε = 0: exactly 3 persistent groups
    of sizes 18, 10, 10; the axis-aligned one is the CCW boundary cycle of 2W+2H = 18 cells with
    uniform stationary distribution 1/18; every axis-aligned cell is transient into it or on it."""
    model = rect(5, 4, 8)
    res = gcm(model, 90 * DEG, 0.0, 1.0)
    assert sorted(res.sizes.tolist()) == [10, 10, 18]
    axis = [g for g in range(res.n_groups) if np.all(model.decode(res.groups[g])[1] % 2 == 0)]
    assert len(axis) == 1 and len(res.groups[axis[0]]) == 18
    assert np.allclose(res.stationary_of(axis[0]), 1 / 18, atol=1e-12)
    aligned = np.flatnonzero(model.decode(np.arange(model.n_cells))[1] % 2 == 0)
    assert all(res.domiciles_of(z) == (axis[0],) for z in aligned)
    diagonal = [g for g in range(res.n_groups) if g != axis[0]]
    assert all(np.all(model.decode(res.groups[g])[1] % 2 == 1) for g in diagonal)
    s = scm(model, 90 * DEG)
    assert sorted(s.periods.tolist()) == [10, 10, 18]
    perimeter = model.position_rc[model.decode(res.groups[axis[0]])[0]]
    on_edge = np.isin(perimeter[:, 0], [0, 3]) | np.isin(perimeter[:, 1], [0, 4])
    assert on_edge.all()


def test_gcm_rows_one_degree_bins():
    """Alam, Bobadilla & Shell 2017, Sec. III-B / thesis §3.3.3 (docs/choices/navigation_coverage.md, "ε counts
    orientation bins"): rows sum to 1; with ε = 5°, 1° bins and r = 0.8 a bump row
    has 0.8 on the nominal bin and 0.02 on each of the 10 others; forward rows a single 1."""
    model = rect(6, 4, 360)
    P = model.transition_matrix(30 * DEG, 5 * DEG, 0.8)
    assert np.allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0, atol=1e-12)
    succ, bump = model.successor(30 * DEG)
    nnz = np.diff(P.indptr)
    assert np.all(nnz[~bump] == 1) and np.all(nnz[bump] == 11)
    for z in np.flatnonzero(bump)[:50]:
        row = P.getrow(z)
        vals = dict(zip(row.indices.tolist(), row.data.tolist(), strict=True))
        assert vals.pop(int(succ[z])) == pytest.approx(0.8)
        assert len(vals) == 10 and np.allclose(list(vals.values()), 0.02)
        p0, k0 = model.decode(z)
        ps, ks = model.decode(np.array(list(vals)))
        assert np.all(ps == p0)
        offsets = sorted(((ks - (k0 + 30)) % 360 + 180) % 360 - 180)
        assert offsets == [-5, -4, -3, -2, -1, 1, 2, 3, 4, 5]
    res = generalized_cell_mapping(P)
    assert np.allclose(res.limiting @ P, res.limiting, atol=1e-12)


def check_gcm_invariants(res, P: sp.csr_matrix, check_scc: bool = True) -> None:
    """Thesis Defs. 3.3.1-3.3.3: persistent groups closed and strongly
    connected, every transient cell reaches one, π_g >= 0, Σ π_g = 1, π = 0 on transient cells,
    π_g P = π_g; the limiting distribution is a stationary probability vector."""
    n = P.shape[0]
    assert np.allclose(np.asarray(P.sum(axis=1)).ravel(), 1.0)
    assert np.array_equal(np.sort(np.concatenate([*res.groups, res.transient])), np.arange(n))
    for g, cells in enumerate(res.groups):
        assert np.all(res.group_of[cells] == g)
        outside = np.ones(n, dtype=bool)
        outside[cells] = False
        assert P[cells][:, outside].sum() == 0  # closed
        if check_scc:
            n_scc, _ = connected_components(P[cells][:, cells], connection="strong")
            assert n_scc == 1
        pi = res.stationary_of(g)
        assert np.all(pi >= 0) and pi.sum() == pytest.approx(1.0)
        assert np.allclose(pi @ P[cells][:, cells], pi, atol=1e-12)
    assert np.all(res.group_of[res.transient] == -1)
    assert np.all(res.stationary[res.transient] == 0) and np.all(res.limiting[res.transient] == 0)
    assert np.all(res.limiting >= 0) and res.limiting.sum() == pytest.approx(1.0)
    assert np.allclose(res.limiting @ P, res.limiting, atol=1e-12)
    assert res.weights.sum() == pytest.approx(1.0) and np.all(res.weights >= 0)
    if len(res.transient):
        assert np.all(np.diff(res.domiciles.indptr) >= 1)  # every transient cell is absorbed
        assert np.allclose(res.absorption.sum(axis=1), 1.0)


def test_gcm_lab_complex_360_bins():
    """Alam, Bobadilla & Shell 2017, Sec. V-C, on the coverage setting (lab_complex, 360 bins, φ =
    30°, ε = 5°, r = 0.8): the invariants hold, the transient domiciles agree with the support of
    the absorption probabilities, and the analysis allocates no O(N²) structure (numpy peak < 256
    MiB, where a dense 65 880² matrix would need 32 GiB)."""
    model = CellModel(get("lab_complex"), n_bins=360)
    P = model.transition_matrix(30 * DEG, 5 * DEG, 0.8)
    tracemalloc.start()
    res = generalized_cell_mapping(P)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 256 * 2**20
    assert res.n_cells == 65880 and res.n_groups >= 1
    check_gcm_invariants(res, res.P)
    support = res.absorption > 1e-12
    assert np.array_equal(support, res.domiciles.toarray())


@pytest.mark.parametrize(("name", "phi_deg"), [("lab_localization_a", 45),
                                               ("lab_localization_b", 135), ("lab_fig1", 90)])
def test_gcm_groups_are_attracting_components(name, phi_deg):
    """Alg. 3 (docs/choices/navigation_coverage.md, "Persistent groups without a transitive closure"): persistent groups
    are the closed SCCs = nx.attracting_components, and the transient cells are everything else (8
    bins, ε = 45°, r = 0.8)."""
    model = CellModel(get(name), n_bins=8)
    P = model.transition_matrix(phi_deg * DEG, 45 * DEG, 0.8)
    res = generalized_cell_mapping(P)
    graph = nx.DiGraph(P)
    assert {frozenset(g.tolist()) for g in res.groups} == {
        frozenset(c) for c in nx.attracting_components(graph)}
    check_gcm_invariants(res, res.P)


def test_open_scc_is_transient():
    """Thesis §5.4.3 (docs/choices/navigation_coverage.md, "Persistent groups without a transitive closure"): a strongly
    connected set that probability can leave is transient (persistence is closedness, not mutual
    reachability). Cells 0 <-> 1 form an SCC leaking into the absorbing cell 2."""
    P = sp.csr_matrix(np.array([[0.0, 0.9, 0.1], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    res = generalized_cell_mapping(P)
    assert res.n_groups == 1 and res.groups[0].tolist() == [2]
    assert res.transient.tolist() == [0, 1]
    assert np.allclose(res.absorption, 1.0)
    # t0 = 1 + 0.9 t1, t1 = 1 + t0  =>  t0 = 1.9 / 0.1
    assert np.allclose(res.absorption_time, [19.0, 20.0])
    assert np.allclose(res.limiting, [0, 0, 1])


@pytest.mark.parametrize(("name", "n_bins", "phi_deg"), [
    ("lab_localization_a", 8, 45), ("lab_localization_b", 8, 135), ("lab_navigation", 8, 90),
    ("lab_complex", 8, 135), ("lab_fig1", 4, 90)])
def test_gcm_eps0_reduces_to_scm(name, n_bins, phi_deg):
    """Thesis §3.3.3: with ε = 0 and r = 1 the GCM is the SCM: persistent groups
    = periodic groups (same numbering by smallest cell), π uniform 1/K on each, transient cells =
    SCM transient cells, absorption 0/1 into the SCM group, and the expected absorption time
    equals the SCM's steps to the cycle."""
    model = CellModel(get(name), n_bins=n_bins)
    s = scm(model, phi_deg * DEG)
    res = gcm(model, phi_deg * DEG, 0.0, 1.0)
    assert res.n_groups == s.n_groups
    for g in range(s.n_groups):
        assert np.array_equal(res.groups[g], np.sort(s.cycles[g]))
        assert np.allclose(res.stationary_of(g), 1.0 / s.periods[g], atol=1e-12)
    assert np.array_equal(res.transient, np.flatnonzero(~s.periodic))
    assert np.allclose(res.absorption, np.eye(s.n_groups)[s.group[res.transient]])
    assert np.allclose(res.absorption_time, s.steps[res.transient])
    weights = np.bincount(s.group, minlength=s.n_groups) / model.n_cells
    assert np.allclose(res.weights, weights)  # basin sizes / N under "all"
    check_gcm_invariants(res, res.P)


def small_chain(seed: int) -> tuple[sp.csr_matrix, list[set[int]]]:
    """A random chain with a period-3 cycle {0,1,2}, an aperiodic pair {3,4}, an absorbing cell 5,
    and 8 transient cells 6..13 (each with a direct edge into a persistent cell, plus random
    edges, so transient cycles exist)."""
    rng = np.random.default_rng(seed)
    n = 14
    P = np.zeros((n, n))
    P[0, 1] = P[1, 2] = P[2, 0] = 1.0
    P[3, 3] = P[3, 4] = 0.5
    P[4, 3] = 1.0
    P[5, 5] = 1.0
    for t in range(6, n):
        targets = rng.choice(n, 3, replace=False)
        P[t, targets] = rng.uniform(0.2, 1.0, 3)
        P[t, rng.integers(0, 6)] += rng.uniform(0.1, 0.4)
        P[t] /= P[t].sum()
    return sp.csr_matrix(P), [{0, 1, 2}, {3, 4}, {5}]


def simulate(P: sp.csr_matrix, starts: np.ndarray, persistent: np.ndarray,
             rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Monte-Carlo walks until the first persistent cell: (that cell, steps taken)."""
    cum = np.cumsum(P.toarray(), axis=1)
    state = starts.copy()
    steps = np.zeros(len(starts), dtype=np.int64)
    moving = ~persistent[state]
    while moving.any():
        idx = np.flatnonzero(moving)
        u = rng.random(len(idx))
        state[idx] = np.minimum((cum[state[idx]] < u[:, None]).sum(axis=1), P.shape[0] - 1)
        steps[idx] += 1
        moving[idx] = ~persistent[state[idx]]
    return state, steps


@pytest.mark.parametrize("seed", range(3))
def test_absorption_matches_monte_carlo(seed):
    """Thesis §5.4 (Isaacson & Madsen): absorption probabilities (I - Q)^-1 R 1_g
    have rows summing to 1 and agree with a Monte-Carlo estimate (20 000 walks per transient cell,
    |error| < 0.02, about 5σ); the expected absorption times (I - Q)^-1 1 agree within 5%."""
    P, groups = small_chain(seed)
    res = generalized_cell_mapping(P)
    assert [set(g.tolist()) for g in res.groups] == groups
    check_gcm_invariants(res, res.P)
    rng = np.random.default_rng(100 + seed)
    runs = 20_000
    starts = np.repeat(res.transient, runs)
    end, steps = simulate(res.P, starts, res.persistent, rng)
    hits = res.group_of[end].reshape(len(res.transient), runs)
    estimate = np.stack([(hits == g).mean(axis=1) for g in range(res.n_groups)], axis=1)
    assert np.allclose(res.absorption.sum(axis=1), 1.0)
    assert np.abs(estimate - res.absorption).max() < 0.02
    mean_steps = steps.reshape(len(res.transient), runs).mean(axis=1)
    assert np.allclose(mean_steps, res.absorption_time, rtol=0.05)


@pytest.mark.parametrize("seed", range(2))
def test_limiting_distribution_is_the_cesaro_limit(seed):
    """docs/choices/navigation_coverage.md, "The limiting distribution starts anywhere": the limiting distribution is
    the Cesàro limit of p(0) P^n (it exists for the period-3 group, where P^n does not converge):
    uniform p(0) over all N cells by default, w_g = (|g| + Σ_t a_tg) / N; the alternative modes
    (uniform over persistent cells, equal weight per group) and a custom p(0) match their own Cesàro
    limits."""
    P, _ = small_chain(seed)
    res = generalized_cell_mapping(P)
    n = P.shape[0]
    dense = P.toarray()
    rng = np.random.default_rng(seed)
    custom = rng.random(n)
    custom /= custom.sum()
    pers = res.persistent.astype(float)
    per_group = np.zeros(n)
    for cells in res.groups:
        per_group[cells[0]] = 1.0 / res.n_groups  # any cell of the group will do
    starts = {"all": np.full(n, 1.0 / n), "persistent": pers / pers.sum(), "group": per_group}
    sizes = res.sizes
    expected_w = (sizes + res.absorption.sum(axis=0)) / n
    assert np.allclose(res.weights, expected_w) and res.mode == "all"
    assert np.allclose(res.group_weights("persistent"), sizes / sizes.sum())
    assert np.allclose(res.group_weights("group"), 1.0 / res.n_groups)
    for start, p0 in [*starts.items(), (custom, custom)]:
        p, total, steps = p0.copy(), np.zeros(n), 30_000
        for _ in range(steps):
            total += p
            p = p @ dense
        cesaro = total / steps
        assert np.allclose(res.limiting_distribution(start), cesaro, atol=2e-3)
        other = generalized_cell_mapping(P, mode=start)
        assert np.allclose(other.limiting, res.limiting_distribution(start))
    assert set(MODES) == {"all", "persistent", "group"}
    # the plain limit does not exist here: from cell 0, p(0) P^n cycles with period 3
    p = np.eye(n)[0]
    assert not np.allclose(p @ dense, p) and np.allclose(p @ dense @ dense @ dense, p)


def test_domicile_sets_two_sinks():
    """Thesis §5.4 (a small 'two_sink' chain): 2 persistent groups and transient domicile sets
    {{0}, {1}, {0, 1}}; single-domicile cells are absorbed with probability 1, the boundary cell
    splits as its one-step probabilities say."""
    P = np.zeros((6, 6))
    P[0, 0] = 1.0  # group 0
    P[1, 1] = 1.0  # group 1
    P[2, 0] = 1.0  # domicile {0}
    P[3, [1, 3]] = 0.5  # domicile {1}
    P[4, [2, 3]] = [0.25, 0.75]  # domiciles {0, 1}
    P[5, [4, 5]] = 0.5  # domiciles {0, 1}
    res = generalized_cell_mapping(sp.csr_matrix(P))
    assert res.n_groups == 2
    sets = res.domicile_groups()
    assert list(sets) == [frozenset({0}), frozenset({1}), frozenset({0, 1})]
    assert [v.tolist() for v in sets.values()] == [[2], [3], [4, 5]]
    assert res.domiciles_of(4) == (0, 1) and res.domiciles_of(1) == (1,)
    a = res.absorption[res.transient_index[[2, 3, 4, 5]]]
    assert np.allclose(a, [[1, 0], [0, 1], [0.25, 0.75], [0.25, 0.75]])
    # t2 = 1; t3 = 1 + t3/2; t4 = 1 + t2/4 + 3 t3/4; t5 = 1 + t4/2 + t5/2
    assert np.allclose(res.absorption_time, [1.0, 2.0, 2.75, 4.75])


@pytest.mark.parametrize(("matrix", "match"), [
    (np.array([[0.5, 0.4], [0.0, 1.0]]), "sum to 1"),
    (np.array([[1.5, -0.5], [0.0, 1.0]]), ">= 0"),
    (np.ones((2, 3)) / 3, "square"),
    (np.array([[np.nan, 1.0], [0.0, 1.0]]), "finite")])
def test_gcm_rejects_non_stochastic(matrix, match):
    """P must be a square row-stochastic matrix (docs/choices/navigation_coverage.md, "The chain is a row-vector
    chain")."""
    with pytest.raises(ConfigError, match=match):
        generalized_cell_mapping(sp.csr_matrix(matrix))


def test_gcm_rejects_bad_mode_and_start():
    P = sp.identity(3, format="csr")
    with pytest.raises(ConfigError, match="mode"):
        generalized_cell_mapping(P, mode="uniform")
    with pytest.raises(ConfigError, match="start"):
        generalized_cell_mapping(P, mode=np.array([0.5, 0.5]))
    res = generalized_cell_mapping(P, mode=np.array([0.2, 0.3, 0.5]))
    assert res.mode == "custom" and np.allclose(res.limiting, [0.2, 0.3, 0.5])
    dense = generalized_cell_mapping(np.array([[0.0, 1.0], [1.0, 0.0]]))  # dense input, period 2
    assert dense.n_groups == 1 and np.allclose(dense.limiting, [0.5, 0.5])


def test_gcm_explicit_zeros_are_not_edges():
    """An explicitly stored 0 is not a transition: cell 0 stays absorbing."""
    P = sp.csr_matrix((np.array([1.0, 0.0, 1.0]), np.array([0, 1, 1]), np.array([0, 2, 3])),
                      shape=(2, 2))
    res = generalized_cell_mapping(P)
    assert res.n_groups == 2 and len(res.transient) == 0
