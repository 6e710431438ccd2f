"""Alg. 5.3 visibility-based deployment: the visible cells, the greedy cover of the seafloor and
the deployment cells kept from it."""

from __future__ import annotations

import numpy as np
import pytest

from baselines.drifters import persistent_behavior, visibility_deployment, visible_cells
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow


def test_visible_cells_are_a_disk_of_whole_cells():
    model = DrifterCells(get_flow("uniform", basin="open"))
    centre = int(model.state_of(0, 10, 14))
    for rule, d, expected in [("corners", 6, None), ("centre", 6, None), ("corners", 0.7, 0)]:
        seen = visible_cells(model, d, rule=rule)[centre].indices
        _, j, i = model.cells[seen].T
        if rule == "corners":
            far = np.hypot(np.abs(j - 10) + 0.5, np.abs(i - 14) + 0.5)
        else:
            far = np.hypot(j - 10, i - 14)
        assert (far <= d).all()
        if expected is not None:
            assert len(seen) == expected
            continue
        # every cell of the grid within the rule is there, and the disk is symmetric
        jj, ii = np.mgrid[0:21, 0:29]
        if rule == "corners":
            inside = np.hypot(np.abs(jj - 10) + 0.5, np.abs(ii - 14) + 0.5) <= d
        else:
            inside = np.hypot(jj - 10, ii - 14) <= d
        assert len(seen) == inside.sum()
        assert set(zip((j - 10).tolist(), (i - 14).tolist(), strict=True)) == {
            (-a, b) for a, b in zip((j - 10).tolist(), (i - 14).tolist(), strict=True)}


@pytest.mark.parametrize("rule", ["corners", "centre"])
@pytest.mark.parametrize("d", [2, 6])
def test_cover_sees_the_whole_seafloor_and_keeps_one_cell_per_persistent_group(rule, d):
    model = DrifterCells(get_flow("two_sink"))
    b = persistent_behavior(model)
    res = visibility_deployment(model, b, d, rule=rule)
    seen = visible_cells(model, d, rule=rule)
    assert seen[res.cover - b.offset].sum(axis=0).min() > 0  # every seafloor cell is seen
    assert len(res.seafloor) == 522
    groups = b.group_of[res.states - b.offset]
    kept = groups[groups >= 0]
    assert len(kept) == len(set(kept.tolist()))  # at most one cell per persistent group
    # C is D without the later cover cells of each persistent group, in cover order
    dropped = [z for z in res.cover if z not in set(res.states.tolist())]
    first = {}
    for z in res.cover:
        first.setdefault(int(b.group_of[z - b.offset]), z)
    assert all(b.group_of[z - b.offset] >= 0 and first[int(b.group_of[z - b.offset])] != z
               for z in dropped)
    assert len(res) <= len(res.cover)


def test_greedy_picks_the_largest_gain_first():
    model = DrifterCells(get_flow("two_sink"))
    b = persistent_behavior(model)
    res = visibility_deployment(model, b, 6)
    counts = np.asarray(visible_cells(model, 6).sum(axis=1)).ravel()
    assert counts[res.cover[0]] == counts.max()
    assert res.cover[0] == np.flatnonzero(counts == counts.max())[0]


def test_three_layers_look_down_on_the_deepest():
    model = DrifterCells(get_flow("scb_like"), t=3600.0)
    b = persistent_behavior(model)
    res = visibility_deployment(model, b, 4)
    floor = model.n_layers - 1
    assert np.array_equal(res.seafloor, model.layer_states(floor))
    assert (model.cells[res.cover, 0] == 0).all()
    seen = visible_cells(model, 4, seafloor=floor)
    assert seen[res.cover].sum(axis=0).min() > 0
    assert len(res) == len(b.groups) == 1  # one persistent group: one drifter suffices


def test_bad_range_is_refused():
    model = DrifterCells(get_flow("two_sink"))
    b = persistent_behavior(model)
    with pytest.raises(ConfigError, match="d: 522 seafloor cells"):
        visibility_deployment(model, b, 0.5)
    with pytest.raises(ConfigError, match="rule"):
        visibility_deployment(model, b, 3, rule="square")
    with pytest.raises(ConfigError, match="d"):
        visibility_deployment(model, b, -1)
