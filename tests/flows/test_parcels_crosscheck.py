"""Cross-check of the continuous drifters against OceanParcels v4 (``AdvectionRK4`` on the same
field, float64 particles): trajectories agree to 1e-9 of the domain's extent.

Both integrate the same A-grid field (bilinear in space, linear in time) with the same RK4
stages, so only round-off separates them. Parcels comes with the ``drifters-check`` extra, which
``make install`` installs; without it this test fails and says how to install it.
"""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym.dynamics.advection import Drifters
from bounce_gym.flows import get_flow
from bounce_gym.flows.parcels_bridge import parcels_advect

TOLERANCE = 1e-9  # of the domain's extent


def ours(field, x, y, layer, dt, n_steps, t=None):
    """Final positions, and which drifters stayed clear of the land rule and inside the range
    of the grid's nodes (Parcels has no land rule and stops outside the nodes)."""
    d = Drifters(field, x, y, layer, t=t)
    clear = np.ones(len(x), dtype=bool)
    for _ in range(n_steps):
        clear &= ~d.step(dt)
        clear &= (d.x >= field.x[0]) & (d.x <= field.x[-1])
        clear &= (d.y >= field.y[0]) & (d.y <= field.y[-1])
    return d.x, d.y, clear


def check(field, x, y, layer, dt, n_steps, t=None, min_clear=20):
    ox, oy, clear = ours(field, x, y, layer, dt, n_steps, t)
    assert clear.sum() >= min_clear
    px, py = parcels_advect(field, x[clear], y[clear], layer, dt, n_steps, t=t)
    extent = max(np.ptp(field.x), np.ptp(field.y))
    assert np.abs(px - ox[clear]).max() <= TOLERANCE * extent
    assert np.abs(py - oy[clear]).max() <= TOLERANCE * extent
    # the comparison means something: the drifters moved
    assert np.hypot(ox - x, oy - y).max() > 0.05 * extent


def test_double_gyre_trajectories_agree_with_parcels():
    rng = np.random.default_rng(0)
    f = get_flow("double_gyre")
    check(f, rng.uniform(0.1, 1.9, 50), rng.uniform(0.1, 0.9, 50), 0, 0.1, 100)


def test_two_sink_trajectories_agree_with_parcels():
    rng = np.random.default_rng(1)
    f = get_flow("two_sink")
    check(f, rng.uniform(2e3, 18e3, 50), rng.uniform(3e3, 15e3, 50), 0, 600.0, 40)


@pytest.mark.parametrize("layer", [0, 2])
def test_scb_like_lonlat_tidal_trajectories_agree_with_parcels(layer):
    rng = np.random.default_rng(2)
    f = get_flow("scb_like")
    j, i = np.nonzero(f.water[layer])
    k = rng.choice(len(j), 60, replace=False)
    check(f, f.x[i[k]] + 0.003, f.y[j[k]] + 0.004, layer, 600.0, 40, t=1800.0)


def test_missing_parcels_is_reported_with_the_extra_to_install(monkeypatch):
    import sys

    from bounce_gym.errors import ConfigError

    monkeypatch.setitem(sys.modules, "parcels", None)  # makes `import parcels` fail
    with pytest.raises(ConfigError, match=r"bounce-gym\[drifters-check\]"):
        parcels_advect(get_flow("two_sink"), [5e3], [5e3], 0, 60.0, 1)
