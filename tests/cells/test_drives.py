"""`ContactDrives` against the cell model stepped tick by tick."""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym import worlds
from bounce_gym.cells import CellModel
from bounce_gym.cells.drives import ContactDrives


@pytest.mark.parametrize("world", ["lab_navigation", "two_rooms"])
def test_every_cells_drive_matches_the_tick_by_tick_drive(world):
    model = CellModel(worlds.get(world), 1.0, 8)
    drives = ContactDrives(model)
    odometer = np.random.default_rng(0).uniform(0, 50, model.n_cells)
    summed = drives.add_hops(np.arange(model.n_cells), odometer)
    moved = 0
    for z in range(model.n_cells):
        p, k = (int(v) for v in model.decode(z))
        ticks, total = 0, float(odometer[z])
        while model.targets[k, p] >= 0:
            target = int(model.targets[k, p])
            gap = model.centres[target] - model.centres[p]
            total += float(np.hypot(gap[0], gap[1]))
            p, ticks = target, ticks + 1
        assert drives.end[z] == k * model.n_positions + p and drives.ticks[z] == ticks
        assert summed[z] == total  # bit for bit: one addition per tick, in order
        moved += ticks > 0
    assert 0 < moved < model.n_cells  # some cells drive, the blocked ones do not
