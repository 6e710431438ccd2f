"""The GCM of drifter layers (thesis Alg. 5.1 PersistentBehavior through the shared Markov layer):
the two-sink structure, closed persistent groups, absorption against Monte Carlo, and the
analytic flows."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow
from bounce_gym.markov.gcm import generalized_cell_mapping, layer_gcm
from bounce_gym.markov.ordering import grid_dissection


@pytest.mark.parametrize("rho", [0.6, 0.8, 0.9])
def test_two_sink_has_two_persistent_and_three_transient_groups(rho):
    res = layer_gcm(DrifterCells(get_flow("two_sink"), rho=rho), 0)
    assert sorted(res.sizes.tolist()) == [20, 25]
    big = int(np.argmax(res.sizes))
    groups = res.domicile_groups()
    sizes = {tuple(sorted(k)): len(v) for k, v in groups.items()}
    assert sizes == {(big,): 55, (1 - big,): 29, (0, 1): 393}
    mean_time = {k: res.absorption_time[res.transient_index[v]].mean() for k, v in groups.items()}
    multi = mean_time.pop(frozenset({0, 1}))
    assert multi > 2 * max(mean_time.values())


MODELS = {
    "two_sink": lambda: DrifterCells(get_flow("two_sink", n_layers=3)),
    "scb_like": lambda: DrifterCells(get_flow("scb_like"), t=3600.0),
    "double_gyre": lambda: DrifterCells(get_flow("double_gyre", spacing=0.05), t=2.0),
    "solid_body": lambda: DrifterCells(get_flow("solid_body"), step="flowline"),
    "uniform": lambda: DrifterCells(get_flow("uniform", v=0.1)),
}


@pytest.mark.parametrize("name", list(MODELS))
def test_rows_sum_to_one_and_persistent_groups_are_closed_classes(name):
    model = MODELS[name]()
    for layer in range(model.n_layers):
        P = model.transition_matrix(layer)
        assert np.allclose(P.sum(axis=1), 1.0, atol=1e-12) and P.data.min() > 0
        res = generalized_cell_mapping(P)
        covered = np.concatenate(res.groups + [res.transient])
        assert np.array_equal(np.sort(covered), np.arange(P.shape[0]))
        for g in res.groups:
            outside = np.ones(P.shape[0], dtype=bool)
            outside[g] = False
            assert P[g][:, outside].nnz == 0  # closed
            n, _ = connected_components(P[g][:, g], directed=True, connection="strong")
            assert n == 1  # every cell communicates with every other


def chains_until_absorbed(model, res, starts, rng, max_steps=10_000):
    """Steps until each chain enters a persistent cell, and the group it enters."""
    state = np.asarray(starts, dtype=np.int64)
    steps = np.zeros(len(state), dtype=np.int64)
    alive = ~res.persistent[state]
    while alive.any():
        assert steps.max() < max_steps
        idx = np.flatnonzero(alive)
        state[idx] = model.sample(state[idx], np.zeros(len(idx), dtype=np.int64), rng)
        steps[idx] += 1
        alive[idx] = ~res.persistent[state[idx]]
    return steps, res.group_of[state]


def test_absorption_times_and_probabilities_match_monte_carlo():
    model = DrifterCells(get_flow("two_sink"), rho=0.8)
    res = layer_gcm(model, 0)
    rng = np.random.default_rng(7)
    groups = res.domicile_groups()
    # from the slowest cell of each transient group, and the most undecided multi-domicile cell
    starts = [int(v[np.argmax(res.absorption_time[res.transient_index[v]])])
              for v in groups.values()]
    multi = groups[frozenset({0, 1})]
    p = res.absorption[res.transient_index[multi]]
    starts.append(int(multi[np.argmax(p.min(axis=1))]))
    assert p.min(axis=1).max() > 0.2 and np.allclose(p.sum(axis=1), 1)
    for z in starts:
        steps, into = chains_until_absorbed(model, res, np.full(6000, z), rng)
        i = res.transient_index[z]
        assert steps.mean() == pytest.approx(res.absorption_time[i], rel=0.05)
        freq = np.bincount(into, minlength=2) / len(into)
        assert np.abs(freq - res.absorption[i]).max() < 0.03


# -- analytic flows ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["solid_body", "uniform"])
@pytest.mark.parametrize("step", ["euler", "flowline"])
def test_with_noise_rotation_and_uniform_flow_are_one_persistent_group(name, step):
    res = layer_gcm(DrifterCells(get_flow(name), rho=0.8, step=step), 0)
    assert res.sizes.tolist() == [522] and len(res.transient) == 0


def cycle_groups(model, res):
    """Persistent groups that are deterministic cycles away from the boundary."""
    P = model.transition_matrix(0)
    return [g for g in res.groups
            if (P[g][:, g].getnnz(axis=1) == 1).all() and not model.boundary[g].any()]


def test_solid_body_flow_lines_close_into_persistent_cycles():
    model = DrifterCells(get_flow("solid_body", basin="open"), rho=1.0, step="flowline")
    res = layer_gcm(model, 0)
    cycles = [g for g in cycle_groups(model, res) if len(g) > 1]
    assert len(cycles) >= 5 and len(cycles) == res.n_groups - 1  # plus the centre, fixed
    f = model.field
    cx, cy = f.x.mean(), f.y.mean()
    for g in cycles:  # each orbit goes once around the centre at a nearly constant radius
        x, y = model.centre(g)
        angles = np.sort(np.arctan2(y - cy, x - cx))
        assert np.diff(np.concatenate((angles, [angles[0] + 2 * np.pi]))).max() < np.pi / 2
        r = np.hypot(x - cx, y - cy)
        assert r.max() - r.min() <= 1.5 * (f.x[1] - f.x[0])


def test_solid_body_euler_unit_steps_spiral_out_to_the_boundary():
    """The explicit Euler step gains radius on every rotation (|1 + i ω Δt| > 1): only the
    centre stays on a closed orbit."""
    model = DrifterCells(get_flow("solid_body", basin="open"), rho=1.0, step="euler")
    res = layer_gcm(model, 0)
    assert [len(g) for g in cycle_groups(model, res)] == [1]
    assert res.n_groups == 2 and model.boundary[res.groups[int(np.argmax(res.sizes))]].any()


def test_uniform_flow_drains_to_the_downstream_boundary():
    model = DrifterCells(get_flow("uniform", u=0.2, v=0.0, basin="open"), rho=0.8)
    # make the boundary absorbing: where does the flow deliver the interior cells?
    P = model.transition_matrix(0).tolil()
    for z in np.flatnonzero(model.boundary):
        P.rows[z], P.data[z] = [z], [1.0]
    res = generalized_cell_mapping(sp.csr_matrix(P))
    assert np.array_equal(res.transient, np.flatnonzero(~model.boundary))
    east = np.array([model.cells[g[0], 2] == model.field.shape[1] - 1 for g in res.groups])
    assert res.absorption[:, east].sum(axis=1).mean() > 0.9
    # the noise is centred on the target, so the drift is one column per step
    z = res.transient_index[model.state_of(0, 10, 1)]
    assert res.absorption_time[z] == pytest.approx(27, rel=0.05)


# -- large-layer machinery: elimination order and grouping ------------------------------------
def test_grid_dissection_is_a_permutation_with_separators_last():
    rows, cols = np.divmod(np.arange(40 * 50), 50)
    order = grid_dissection(rows, cols, width=2)
    assert np.array_equal(np.sort(order), np.arange(40 * 50))
    # the first cut halves the longer side (50 columns) with a band of 2 columns, ordered last
    band = order[-80:]
    assert np.ptp(cols[band]) == 1 and len(np.unique(rows[band])) == 40
    assert set(cols[band].tolist()) == {24, 25}  # at the median column, 24.5, rounded down


@pytest.mark.parametrize("name, layer", [("two_sink", 0), ("scb_like", 2)])
def test_the_elimination_order_changes_no_result(name, layer):
    model = DrifterCells(get_flow(name), t=None if name == "two_sink" else 3600.0)
    ordered = layer_gcm(model, layer)
    assert ordered.order is not None
    plain = generalized_cell_mapping(model.transition_matrix(layer))
    assert np.allclose(ordered.absorption_time, plain.absorption_time, rtol=1e-9)
    assert np.allclose(ordered.absorption, plain.absorption, atol=1e-12)
    assert np.allclose(ordered.limiting, plain.limiting, atol=1e-12)
    with pytest.raises(ConfigError, match="order: expected a permutation"):
        generalized_cell_mapping(model.transition_matrix(layer), order=[0, 0, 1])


def test_domicile_groups_match_the_rows_of_the_domicile_matrix():
    res = layer_gcm(DrifterCells(get_flow("scb_like"), t=12 * 3600.0), 0)
    d = res.domiciles.tolil()
    expected: dict[frozenset, list[int]] = {}
    for i, cell in enumerate(res.transient):
        expected.setdefault(frozenset(d.rows[i]), []).append(int(cell))
    got = res.domicile_groups()
    assert {k: v.tolist() for k, v in got.items()} == expected
    assert list(got) == sorted(got, key=lambda k: (len(k), sorted(k)))
