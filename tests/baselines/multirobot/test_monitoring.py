"""Persistent monitoring (Alam & Bobadilla 2020, §4.2, Algorithm 2; choices where the article
is open: docs/choices/multirobot.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines.multirobot.monitoring import (
    REJECTED,
    default_regions,
    joint_monitoring_cycles,
    joint_successor,
    region_indices,
)
from bounce_gym.cells import CellModel, too_close
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym.markov.scm import simple_cell_mapping
from bounce_gym.worlds import world_from_grid

ROOM = world_from_grid(np.ones((6, 8), dtype=bool), name="room_8x6")


@pytest.fixture(scope="module")
def model():
    return CellModel(ROOM)


@pytest.fixture(scope="module", params=[45, 90])
def result(request, model):
    phi = math.radians(request.param)
    return joint_monitoring_cycles(model, [phi, phi])


def test_r_positive_for_45_and_90(result):
    assert result.r > 0
    assert len(result.cycles) == len(result.periods) == len(result.basins) == result.r
    assert result.n_groups > result.r  # the sink is a group and is never accepted


def test_cycles_are_periodic_groups(result):
    succ = result.scm.successor
    for cyc, period in zip(result.cycles, result.periods, strict=True):
        assert len(cyc) == period == len(np.unique(cyc))
        assert np.array_equal(succ[cyc], np.roll(cyc, -1))
        assert result.sink not in cyc


def test_cycles_collision_free_and_visit_regions(result, model):
    f1, f2 = (set(f.tolist()) for f in result.regions)
    for cyc in result.cycles:
        z1, z2 = result.split(cyc)
        p1, p2 = model.decode(z1)[0], model.decode(z2)[0]
        assert np.all(p1 != p2)
        assert f1 & set(p1.tolist()) and f2 & set(p2.tolist())


def test_period_is_lcm_of_individual_periods(result, model):
    """Robots ignore each other: a joint cycle runs two individual cycles in lock step."""
    singles = [simple_cell_mapping(model.successor(phi)[0]) for phi in result.phis]
    for cyc, period in zip(result.cycles, result.periods, strict=True):
        z1, z2 = result.split(cyc[:1])
        k1, k2 = singles[0].period_of(z1)[0], singles[1].period_of(z2)[0]
        assert period == math.lcm(int(k1), int(k2))
        assert period % k1 == 0 and period % k2 == 0


def test_basins_lead_into_their_group(result):
    res = result.scm
    for g, basin in zip(result.accepted, result.basins, strict=True):
        transient = res.transient_trajectory(g)
        assert len(transient) == basin
        # transient cells are collision-free too: none of them maps to the sink
        assert not np.any(res.successor[transient] == result.sink)


def test_labels_partition_joint_cells(result):
    """docs/choices/multirobot.md, "Algorithm 2's bookkeeping": every joint cell, the sink included, ends up
    exactly one of accepted-periodic (P_g), accepted-transient (Q_g) or rejected."""
    label, periodic = result.label, result.periodic
    n_joint = result.model.n_cells ** 2 + 1
    assert label.shape == periodic.shape == (n_joint,)
    assert np.issubdtype(label.dtype, np.integer)
    assert set(np.unique(label).tolist()) <= {REJECTED, *range(result.r)}
    accepted = label >= 0
    n_p, n_q = int((accepted & periodic).sum()), int((accepted & ~periodic).sum())
    n_rej = int((label == REJECTED).sum())
    assert n_p + n_q + n_rej == n_joint
    assert n_p == int(result.periods.sum()) and n_q == int(result.basins.sum())
    # the sink and its whole basin are rejected
    sink_group = result.scm.group[result.sink]
    assert label[result.sink] == REJECTED
    assert np.all(label[result.scm.group == sink_group] == REJECTED)


def test_labels_follow_accepted_groups(result):
    """The cells labelled g are exactly SCM group ``accepted[g]``: its cycle P_g and its
    transients Q_g (|Q_g| = ``basins[g]``); the other groups are rejected."""
    group, periodic = result.scm.group, result.periodic
    for g, (scm_g, cyc, basin) in enumerate(zip(result.accepted, result.cycles, result.basins,
                                                strict=True)):
        mine = result.label == g
        assert np.array_equal(mine, group == scm_g)
        assert np.array_equal(np.flatnonzero(mine & periodic), np.sort(cyc))
        assert int((mine & ~periodic).sum()) == basin
    rejected = ~np.isin(group, result.accepted)
    assert np.array_equal(result.label == REJECTED, rejected)


def test_sink_is_absorbing(model):
    phi = math.radians(90)
    succ, n_coll = joint_successor(model, [phi, phi])
    n = model.n_cells
    sink = n * n
    assert len(succ) == sink + 1 and succ[sink] == sink
    z1, z2 = np.divmod(np.arange(sink), n)
    p1, p2 = model.decode(z1)[0], model.decode(z2)[0]
    same = p1 == p2
    # crossing diagonals: both robots at one midpoint half-way through the tick, not a swap
    s = model.successor(phi)[0]
    q1, q2 = model.decode(s[z1])[0], model.decode(s[z2])[0]
    rc = model.position_rc
    mid = np.all(rc[p1] + rc[q1] == rc[p2] + rc[q2], axis=1)
    cross = mid & ~same & ~((q1 == p2) & (q2 == p1))
    assert cross.any()
    assert n_coll == model.n_positions * model.n_bins**2 + cross.sum()
    assert np.all(succ[:sink][same | cross] == sink)
    assert np.all(succ[:sink][~(same | cross)] < sink)
    # the sink is a period-1 group that is rejected
    res = joint_monitoring_cycles(model, [phi, phi])
    assert res.scm.periods[res.scm.group[sink]] == 1
    assert res.scm.group[sink] not in res.accepted


def test_product_structure_without_collisions(model):
    """Derived property: individual periods p1, p2 give gcd(p1, p2) joint groups of period
    lcm(p1, p2) without the collision filter; the filter only removes groups."""
    phi1, phi2 = math.radians(90), math.radians(45)
    s1, s2 = model.successor(phi1)[0], model.successor(phi2)[0]
    g1, g2 = simple_cell_mapping(s1), simple_cell_mapping(s2)
    expected = sorted(math.lcm(int(a), int(b)) for a in g1.periods for b in g2.periods
                      for _ in range(math.gcd(int(a), int(b))))
    product = simple_cell_mapping((s1[:, None] * model.n_cells + s2[None, :]).ravel())
    assert sorted(product.periods.tolist()) == expected
    res = joint_monitoring_cycles(model, [phi1, phi2], mode="any")
    assert res.n_groups - 1 <= len(expected)  # minus the sink
    # in this room every 90°/45° pair of cycles meets: no accepted group (a true negative)
    assert res.r == 0 and res.n_groups == 1


def test_swaps_forbidden_is_stricter(model):
    phi = math.radians(45)
    loose = joint_monitoring_cycles(model, [phi, phi])
    strict = joint_monitoring_cycles(model, [phi, phi], forbid_swaps=True)
    assert strict.r <= loose.r
    assert strict.n_collision_cells >= loose.n_collision_cells


def test_min_sep_zero_is_same_cell(model):
    """docs/choices/multirobot.md, "Robot–robot conflicts on the grid": ``min_sep_cells=0`` is the same-cell
    rule (the identity matrix) and the default."""
    assert np.array_equal(too_close(model.position_rc, 0), np.eye(model.n_positions, dtype=bool))
    phi = math.radians(90)
    for swaps in (False, True):
        succ, n_coll = joint_successor(model, [phi, phi], swaps)
        succ0, n_coll0 = joint_successor(model, [phi, phi], swaps, min_sep_cells=0)
        assert np.array_equal(succ, succ0) and n_coll == n_coll0
        a = joint_monitoring_cycles(model, [phi, phi], forbid_swaps=swaps)
        b = joint_monitoring_cycles(model, [phi, phi], forbid_swaps=swaps, min_sep_cells=0)
        assert np.array_equal(a.accepted, b.accepted) and np.array_equal(a.label, b.label)


@pytest.mark.parametrize("deg", [90, 135])
def test_min_sep_cells_shrinks_accepted_set(model, deg):
    """A larger separation only adds collision cells, so each accepted cycle at separation k is
    an accepted cycle at k - 1 and r is non-increasing; every accepted cycle keeps Chebyshev
    separation > k at every step."""
    phi = math.radians(deg)
    results = [joint_monitoring_cycles(model, [phi, phi], min_sep_cells=k) for k in (0, 1, 2)]
    rs = [res.r for res in results]
    assert rs[0] > rs[1] > 0 and rs[1] >= rs[2]
    for k, res in enumerate(results):
        z1, z2 = res.split(np.concatenate(res.cycles))
        rc1 = model.position_rc[model.decode(z1)[0]]
        rc2 = model.position_rc[model.decode(z2)[0]]
        assert np.all(np.abs(rc1 - rc2).max(axis=1) > k)
        if k:
            before = {tuple(c.tolist()) for c in results[k - 1].cycles}
            assert {tuple(c.tolist()) for c in res.cycles} <= before
            assert res.n_collision_cells > results[k - 1].n_collision_cells


@pytest.mark.parametrize("bad", [-1, 1.5, "1", True, None])
def test_min_sep_cells_rejects_bad_values(model, bad):
    phi = math.radians(90)
    with pytest.raises(ConfigError, match="min_sep_cells"):
        joint_monitoring_cycles(model, [phi, phi], min_sep_cells=bad)
    with pytest.raises(ConfigError, match="min_sep_cells"):
        joint_successor(model, [phi, phi], min_sep_cells=bad)


def test_modes(model):
    phi = math.radians(90)
    visit = joint_monitoring_cycles(model, [phi, phi], mode="visit")
    anyr = joint_monitoring_cycles(model, [phi, phi], mode="any")
    assert set(visit.accepted.tolist()) <= set(anyr.accepted.tolist())
    # "cover" with regions taken from an accepted cycle accepts that cycle
    cyc = visit.cycles[0]
    z1, z2 = visit.split(cyc)
    f1, f2 = np.unique(model.decode(z1)[0]), np.unique(model.decode(z2)[0])
    cover = joint_monitoring_cycles(model, [phi, phi], regions=[f1, f2], mode="cover")
    assert visit.accepted[0] in cover.accepted
    with pytest.raises(ConfigError):
        joint_monitoring_cycles(model, [phi, phi], mode="bogus")


def test_regions(model):
    f1, f2 = default_regions(model)
    assert len(f1) + len(f2) == model.n_positions and not set(f1) & set(f2)
    assert model.position_rc[f1, 1].max() < model.position_rc[f2, 1].min()
    assert np.array_equal(region_indices(model, model.position_rc[f1]), f1)
    with pytest.raises(ConfigError):
        region_indices(model, [[100, 100]])


@pytest.mark.parametrize("deg", [45, 90])
def test_replay_in_env(model, deg):
    """Every accepted cycle, replayed in the cell backend, repeats with its period, never puts both
    robots in one cell and visits each robot's region every period."""
    phi = math.radians(deg)
    res = joint_monitoring_cycles(model, [phi, phi])
    env = MultiBounceEnv(world=ROOM, n_robots=2, backend="cell", robot_radius=0.0,
                         robot_collisions="ignore", angles=[[deg], [deg]], step_mode="tick",
                         max_cycles=10_000)
    actions = {"robot_0": 0, "robot_1": 0}
    f1, f2 = (set(f.tolist()) for f in res.regions)
    for cyc, period in zip(res.cycles, res.periods, strict=True):
        _, info = env.reset(seed=0, options=res.start_options(int(cyc[0])))
        seen = [set(), set()]
        for t in range(2 * int(period)):
            z = [int(model.cell_of(info[a]["position"], info[a]["heading"])[0])
                 for a in ("robot_0", "robot_1")]
            assert z[0] * model.n_cells + z[1] == cyc[t % period]
            p = [model.decode(zi)[0] for zi in z]
            assert p[0] != p[1]
            seen[0].add(int(p[0]))
            seen[1].add(int(p[1]))
            if (t + 1) % period == 0:
                assert seen[0] & f1 and seen[1] & f2
                seen = [set(), set()]
            _, _, _, _, info = env.step(actions)
    env.close()


@pytest.mark.parametrize("deg", [45, 90])
def test_zoo_grid_10x10_r_positive(deg):
    from bounce_gym.worlds import get

    model = CellModel(get("grid_10x10"))
    phi = math.radians(deg)
    res = joint_monitoring_cycles(model, [phi, phi])
    assert res.r > 0
    for cyc in res.cycles:
        z1, z2 = res.split(cyc)
        assert np.all(model.decode(z1)[0] != model.decode(z2)[0])


def test_accepted_cycles_never_cross_diagonally():
    """docs/choices/multirobot.md, "Robot–robot conflicts on the grid": two robots whose diagonal moves
    cross meet at the shared corner half-way through the tick, so no accepted cycle may contain
    such a step (grid_10x10 at φ = 90° accepted 6 such cycles of 73 before the rule)."""
    from bounce_gym.worlds import get

    model = CellModel(get("grid_10x10"))
    phi = math.radians(90)
    res = joint_monitoring_cycles(model, [phi, phi])
    rc = model.position_rc
    for cyc in res.cycles:
        z1, z2 = res.split(cyc)
        a, b = rc[model.decode(z1)[0]], rc[model.decode(z2)[0]]
        a1, b1 = np.roll(a, -1, axis=0), np.roll(b, -1, axis=0)
        swap = np.all(a == b1, axis=1) & np.all(b == a1, axis=1)
        assert not np.any(np.all(a + a1 == b + b1, axis=1) & ~swap)
    assert res.r > 0
