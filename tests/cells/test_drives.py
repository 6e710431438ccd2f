"""`ContactDrives` against the cell model stepped tick by tick."""

from __future__ import annotations

import pytest

from bounce_gym import worlds
from bounce_gym.cells import CellModel
from bounce_gym.cells.drives import ContactDrives


@pytest.mark.parametrize("world", ["lab_navigation", "two_rooms"])
def test_every_cells_drive_matches_the_tick_by_tick_drive(world):
    model = CellModel(worlds.get(world), 1.0, 8)
    drives = ContactDrives(model)
    moved = 0
    for z in range(model.n_cells):
        p, k = (int(v) for v in model.decode(z))
        ticks = 0
        while model.targets[k, p] >= 0:
            target = int(model.targets[k, p])
            p, ticks = target, ticks + 1
        assert drives.end[z] == k * model.n_positions + p and drives.ticks[z] == ticks
        moved += ticks > 0
    assert 0 < moved < model.n_cells  # some cells drive, the blocked ones do not
