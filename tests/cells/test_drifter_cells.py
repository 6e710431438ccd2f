"""The drifter cell model (bounce_gym.cells.drifter): states, the unit-step map, ρ, boundary
cells, vertical actions and sampling."""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym.cells import DOWN, DRIFT, UP, DrifterCells
from bounce_gym.errors import ActionError, ConfigError, InvalidFlowError
from bounce_gym.flows import FlowField, get_flow


def uniform_field(u, v, shape=(5, 6), crs="xy", y=None, land=None):
    ny, nx = shape
    ones = np.ones((1, ny, nx))
    x = np.arange(nx, dtype=float) if crs == "lonlat" else 1000.0 * np.arange(nx)
    y = y if y is not None else 1000.0 * np.arange(ny)
    return FlowField(u * ones, v * ones, x=x, y=y, crs=crs, land=land)


def test_state_numbering_is_layer_major_then_row_major():
    f = get_flow("scb_like")
    m = DrifterCells(f, t=3600.0)
    assert m.n_states == int(f.water.sum()) and m.n_layers == 3
    assert np.array_equal(m.offsets, np.concatenate(([0], np.cumsum(f.water.sum(axis=(1, 2))))))
    assert np.all(np.diff(m.cells[:, 0]) >= 0)
    first = m.cells[m.offsets[1]]
    assert first[0] == 1 and m.index[tuple(first)] == m.offsets[1]
    assert np.array_equal(m.state_of(*m.cells.T), np.arange(m.n_states))
    assert m.state_of(0, f.shape[0] - 1, f.shape[1] - 1) == -1  # land corner
    assert m.layer_states(2).tolist() == list(range(m.offsets[2], m.offsets[3]))
    x, y = m.centre([5, m.offsets[2] + 7])
    assert m.state_at_point(x, y, [0, 2]).tolist() == [5, m.offsets[2] + 7]
    assert m.state_at_point(f.x[-1], f.y[-1], 0) == -1


@pytest.mark.parametrize("u, v, step", [
    (1.0, 0.0, (0, 1)), (0.0, -1.0, (-1, 0)), (1.0, 1.0, (1, 1)), (-1.0, 0.2, (0, -1)),
    (1.0, np.tan(np.radians(30)), (1, 1)),  # the ½ tie counts as a step
    (1.0, np.tan(np.radians(29)), (0, 1)),
])  # fmt: skip
def test_unit_step_is_a_king_move_along_the_flow(u, v, step):
    m = DrifterCells(uniform_field(u, v))
    z = m.state_of(0, 2, 2)
    assert tuple(m.cells[m.mapped[z], 1:] - m.cells[z, 1:]) == step


def test_unit_step_is_measured_in_cells_on_a_lonlat_grid():
    # at 60°N a degree of longitude is half a degree of latitude: equal u and v in m/s make
    # the heading in cells atan2(1, 2) = 26.6°, an eastward king move
    f = uniform_field(1.0, 1.0, crs="lonlat", y=60.0 + np.arange(5.0))
    m = DrifterCells(f)
    z = m.state_of(0, 2, 2)
    assert tuple(m.cells[m.mapped[z], 1:] - m.cells[z, 1:]) == (0, 1)


def test_still_water_and_steps_onto_land_stay():
    land = np.zeros((5, 6), dtype=bool)
    land[2, 3] = True
    m = DrifterCells(uniform_field(1.0, 0.0, land=land))
    z = m.state_of(0, 2, 2)
    assert m.mapped[z] == z and m.boundary[z]
    still = DrifterCells(uniform_field(0.0, 0.0))
    assert np.array_equal(still.mapped, np.arange(still.n_states))


def test_rows_follow_rho_and_the_target_neighbourhood():
    m = DrifterCells(uniform_field(1.0, 0.0, shape=(7, 8)), rho=0.7)
    P = m.drift_matrix().toarray()
    z = m.state_of(0, 3, 3)
    target = m.state_of(0, 3, 4)
    assert P[z, target] == pytest.approx(0.7)
    neighbours = [m.state_of(0, 3 + dj, 4 + di) for dj in (-1, 0, 1) for di in (-1, 0, 1)
                  if dj or di]
    assert np.allclose(P[z, neighbours], 0.3 / 8) and P[z].sum() == pytest.approx(1.0)
    # a cell whose target is next to the edge: A(z) has the target's 5 water neighbours
    z = m.state_of(0, 3, 6)
    assert not m.boundary[z] and P[z, m.state_of(0, 3, 7)] == pytest.approx(0.7)
    assert np.count_nonzero(P[z]) == 6 and np.allclose(P[z][(P[z] > 0) & (P[z] < 0.5)], 0.3 / 5)


def test_boundary_cells_are_uniform_over_themselves_and_water_neighbours():
    land = np.zeros((5, 6), dtype=bool)
    land[2, 3] = True
    m = DrifterCells(uniform_field(1.0, 0.0, land=land))
    P = m.drift_matrix().toarray()
    corner = m.state_of(0, 0, 0)
    assert m.boundary[corner] and np.allclose(P[corner, P[corner] > 0], 1 / 4)
    beside_land = m.state_of(0, 2, 2)
    row = P[beside_land]
    assert np.count_nonzero(row) == 8 and np.allclose(row[row > 0], 1 / 8)
    assert m.boundary.sum() == 18 + 8  # the grid's rim and the ring around the land cell
    # rho = 1: interior rows are deterministic, boundary rows are not
    det = DrifterCells(uniform_field(1.0, 0.0, land=land), rho=1.0).drift_matrix()
    interior = np.flatnonzero(~m.boundary)
    assert (det[interior].getnnz(axis=1) == 1).all()


def test_vertical_actions_and_legal_mask():
    f = get_flow("scb_like")
    m = DrifterCells(f, t=0.0)
    lay, j, i = m.cells.T
    assert not m.legal[lay == 0, UP].any() and not m.legal[lay == 2, DOWN].any()
    assert m.legal[:, DRIFT].all()
    down_ok = (lay < 2) & f.water[np.minimum(lay + 1, 2), j, i]
    assert np.array_equal(m.legal[:, DOWN], down_ok)
    assert not down_ok[lay == 0].all()  # the shelf: some surface cells have land below
    legal_up = np.flatnonzero(m.legal[:, UP])
    assert np.array_equal(m.cells[m.vertical[legal_up, UP]],
                          m.cells[legal_up] - np.array([1, 0, 0]))
    drift, up, down = m.action_matrices()
    assert np.allclose(drift.sum(axis=1), 1)
    assert np.array_equal(np.asarray(up.sum(axis=1)).ravel(), m.legal[:, UP].astype(float))
    assert np.array_equal(np.asarray(down.sum(axis=1)).ravel(), m.legal[:, DOWN].astype(float))
    # the drift matrix is block-diagonal: no drift changes layer
    coo = drift.tocoo()
    assert np.array_equal(lay[coo.row], lay[coo.col])


def test_sampling_follows_the_rows_and_is_seeded():
    m = DrifterCells(get_flow("two_sink"), rho=0.8)
    z = int(np.flatnonzero(~m.boundary)[100])
    states = np.full(40_000, z)
    draws = m.sample(states, np.zeros_like(states), np.random.default_rng(1))
    freq = np.bincount(draws, minlength=m.n_states) / len(draws)
    assert np.abs(freq - m.drift_matrix()[z].toarray().ravel()).max() < 0.01
    again = m.sample(states, np.zeros_like(states), np.random.default_rng(1))
    assert np.array_equal(draws, again)


def test_sampling_vertical_moves_and_errors():
    m = DrifterCells(get_flow("scb_like"), t=0.0)
    s = int(np.flatnonzero(m.legal[:, DOWN])[0])
    rng = np.random.default_rng(0)
    assert m.sample([s], [DOWN], rng)[0] == m.vertical[s, DOWN]
    with pytest.raises(ActionError, match=r"up is illegal in state 0 \(cell \(0, 0, 0\)\)"):
        m.sample([0], [UP], rng)
    with pytest.raises(ActionError, match="codes 0"):
        m.sample([0], [3], rng)
    with pytest.raises(ActionError, match="states"):
        m.sample([m.n_states], [0], rng)


def test_time_picks_the_snapshot():
    f = get_flow("scb_like")
    a, b = DrifterCells(f, t=3600.0), DrifterCells(f, t=12 * 3600.0)
    assert not np.array_equal(a.mapped, b.mapped)
    with pytest.raises(InvalidFlowError, match="^t: expected a finite time"):
        DrifterCells(f)
    with pytest.raises(InvalidFlowError, match="outside the field's time range"):
        DrifterCells(f, t=30 * 3600.0)
    held = DrifterCells(f, t=30 * 3600.0, outside="hold")
    assert np.array_equal(held.mapped, DrifterCells(f, t=24 * 3600.0).mapped)


def test_constructor_checks():
    f = get_flow("two_sink")
    with pytest.raises(ConfigError, match="rho"):
        DrifterCells(f, rho=0.0)
    with pytest.raises(ConfigError, match="rho"):
        DrifterCells(f, rho=1.5)
    with pytest.raises(ConfigError, match="field"):
        DrifterCells("two_sink")
    with pytest.raises(ConfigError, match="step"):
        DrifterCells(f, step="rk45")
    with pytest.raises(ConfigError, match="layer"):
        DrifterCells(f).layer_states(1)


def test_sample_one_draws_what_sample_draws():
    model = DrifterCells(get_flow("two_sink", n_layers=3), rho=0.7)
    rng = np.random.default_rng(0)
    states = rng.integers(model.n_states, size=400)
    actions = np.array([rng.choice(np.flatnonzero(model.legal[s])) for s in states])
    batch = np.random.default_rng(1)
    single = np.random.default_rng(1)
    expected = [int(model.sample(np.array([s]), np.array([a]), batch)[0])
                for s, a in zip(states, actions, strict=True)]
    got = [model.sample_one(int(s), int(a), single) for s, a in zip(states, actions, strict=True)]
    assert got == expected
    assert batch.random() == single.random()  # the same number of draws
    with pytest.raises(ActionError, match="up is illegal"):
        model.sample_one(int(model.layer_states(0)[0]), UP, single)
    with pytest.raises(ActionError, match="expected a state"):
        model.sample_one(model.n_states, DRIFT, single)
