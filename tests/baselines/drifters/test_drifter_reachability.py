"""Alg. 5.4 reachability across layers: vertical moves only at x_I, or anywhere."""

from __future__ import annotations

import numpy as np
import pytest

from baselines.drifters import persistent_behavior, persistent_reachability
from bounce_gym.cells import DOWN, DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow


@pytest.fixture(scope="module")
def scb():
    return DrifterCells(get_flow("scb_like"), t=3600.0)


def test_column_then_drift_equals_the_union_of_the_layers_reach(scb):
    # a surface cell whose column reaches the bottom, and one on the shelf (land below)
    full = [z for z in scb.layer_states(0) if scb.vertical[scb.vertical[z, DOWN], DOWN] >= 0]
    shelf = [z for z in scb.layer_states(0) if scb.vertical[z, DOWN] < 0]
    assert full and shelf
    for start, depth in ((full[0], 3), (shelf[0], 1)):
        res = persistent_reachability(scb, start)
        assert len(res.column) == depth and res.column[0] == start
        assert (scb.cells[res.column, 1:] == scb.cells[start, 1:]).all()
        assert res.reached[res.column].all()
        expected = np.zeros(scb.n_states, dtype=bool)
        for state in res.column:  # Alg. 5.4 line 3-4: each layer's Alg. 5.1 reach
            b = persistent_behavior(scb, int(scb.cells[state, 0]))
            expected[b.states] = b.reach([state])
        assert np.array_equal(res.reached, expected)
        wide = persistent_reachability(scb, start, vertical_anywhere=True)
        assert (wide.reached >= res.reached).all()


def test_single_layer_reach_is_the_descendants():
    model = DrifterCells(get_flow("two_sink"))
    b = persistent_behavior(model)
    start = int(b.groups[0][0])
    res = persistent_reachability(model, start)
    assert np.array_equal(res.reached, b.reach([start]))
    assert res.reached.sum() == len(b.groups[0])  # a persistent group is closed
    assert np.array_equal(res.states(), np.sort(b.groups[0]))


def test_vertical_anywhere_can_leave_a_closed_group():
    model = DrifterCells(get_flow("two_sink", n_layers=3))
    b = persistent_behavior(model)
    start = int(b.groups[0][0])
    only_here = persistent_reachability(model, start)
    anywhere = persistent_reachability(model, start, vertical_anywhere=True)
    assert anywhere.reached.sum() > only_here.reached.sum()
    assert (anywhere.reached >= only_here.reached).all()


def test_start_must_be_a_surface_state(scb):
    with pytest.raises(ConfigError, match="start"):
        persistent_reachability(scb, int(scb.offsets[1]))
    with pytest.raises(ConfigError, match="vertical_anywhere"):
        persistent_reachability(scb, 0, vertical_anywhere=1)
