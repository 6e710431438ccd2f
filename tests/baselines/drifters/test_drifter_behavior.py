"""Alg. 5.1 through `persistent_behavior`: the two-sink structure of thesis Fig. 5.7/5.8, the
plain-data invariants, and the analytic flows."""

from __future__ import annotations

import numpy as np
import pytest

from baselines.drifters import persistent_behavior
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow


@pytest.mark.parametrize("rho", [0.6, 0.8, 0.9])
def test_two_sink_structure(rho):
    b = persistent_behavior(DrifterCells(get_flow("two_sink"), rho=rho))
    assert sorted(len(g) for g in b.groups) == [20, 25]
    big = int(np.argmax([len(g) for g in b.groups]))
    sizes = {tuple(sorted(k)): len(v) for k, v in b.transient_groups.items()}
    assert sizes == {(big,): 55, (1 - big,): 29, (0, 1): 393}
    mean = {k: b.absorption_time[v - b.offset].mean() for k, v in b.transient_groups.items()}
    multi = mean.pop(frozenset({0, 1}))
    assert multi > max(mean.values())  # thesis Fig. 5.8: the boundary region is slowest


def test_plain_data_partitions_the_layer_and_is_consistent():
    model = DrifterCells(get_flow("two_sink", n_layers=3))
    b = persistent_behavior(model, layer=1)
    assert b.offset == model.offsets[1] and np.array_equal(b.states, model.layer_states(1))
    parts = np.sort(np.concatenate(list(b.groups) + list(b.transient_groups.values())))
    assert np.array_equal(parts, b.states)
    for g, cells in enumerate(b.groups):
        assert (b.group_of[cells - b.offset] == g).all()
        assert b.reach(cells[:1]).sum() == len(cells)  # closed and communicating
    for k, (key, cells) in enumerate(b.transient_groups.items()):
        local = cells - b.offset
        assert (b.transient_group_of[local] == k).all() and (b.group_of[local] == -1).all()
        # the domiciles are exactly the groups the cell leads to
        for z in cells[:: max(1, len(cells) // 7)]:
            reached = b.reach([z])
            assert {g for g, c in enumerate(b.groups) if reached[c - b.offset].any()} == key
            assert np.flatnonzero(b.absorption[z - b.offset] > 0).tolist() == sorted(key)
    assert np.allclose(b.absorption.sum(axis=1), 1.0)
    assert (b.absorption_time[b.persistent] == 0).all()
    assert (b.absorption_time[~b.persistent] >= 1).all()


def test_bad_input_is_refused():
    model = DrifterCells(get_flow("two_sink"))
    with pytest.raises(ConfigError, match="layer"):
        persistent_behavior(model, layer=1)
    with pytest.raises(ConfigError, match="model"):
        persistent_behavior(get_flow("two_sink"))
    with pytest.raises(ConfigError, match="states"):
        persistent_behavior(model).reach([522])


# -- analytic flows, as the cell model has them (phase 1) -------------------------------------
@pytest.mark.parametrize("name", ["solid_body", "uniform"])
def test_with_noise_rotation_and_uniform_flow_mix_the_whole_basin(name):
    b = persistent_behavior(DrifterCells(get_flow(name), rho=0.8))
    assert [len(g) for g in b.groups] == [522] and not b.transient_groups


def test_solid_body_flow_lines_are_persistent_cycles_and_euler_steps_spiral_out():
    orbit = persistent_behavior(DrifterCells(get_flow("solid_body", basin="open"), rho=1.0,
                                             step="flowline"))
    euler = persistent_behavior(DrifterCells(get_flow("solid_body", basin="open"), rho=1.0))
    cycles = [g for g in orbit.groups
              if len(g) > 1 and (orbit.graph[g][:, g].getnnz(axis=1) == 1).all()]
    assert len(cycles) >= 5
    assert len(euler.groups) == 2  # the fixed centre and the boundary the spiral ends on

