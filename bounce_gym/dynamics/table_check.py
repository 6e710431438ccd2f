"""How far the tabulated bump-to-bump map (`bounce_gym.dynamics.bump_table`) is from the
simulator it tabulates, on poses it was not built from.

`table_error` draws held-out contact poses *from the simulator itself* — robots placed at random
in the free space drive to a wall (`bump_sampler.reset_drives`) and bump once more with a random
rotation (`bump_sampler.simulate_bumps`), so the poses include the corners and the poses a hair
clear of a wall that real bumps leave — and then bumps each of them once more with a rotation
drawn uniformly from [0, 2π), through the simulator and through the table with the same
rotation (no noise: the table applies the noise model's draw as given, so the map itself is
compared). It also compares the reset drives of the first step. For both it reports the share
of outcomes whose next decision state (`BumpStates`) is the same, the distribution of the
distance between the two contact points (also over the robots that moved), and the shares with the same clock and a clock within
one tick, over the outcomes where the simulator's robot arrived (its own lost robots are
counted apart). Shares carry Wilson 95 % intervals; quantiles the distribution-free 95 %
interval of order statistics.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics.bump_sampler import default_max_ticks, reset_drives, simulate_bumps
from bounce_gym.dynamics.bump_table import BumpTable

#: quantiles of the position error reported
QUANTILES = (0.5, 0.9, 0.99)


def wilson(hits: int, n: int, z: float = 1.96) -> list[float]:
    """The Wilson score interval (95 % by default) of a share ``hits`` / ``n``."""
    if n == 0:
        return [math.nan, math.nan]
    p = hits / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return [max(0.0, centre - half), min(1.0, centre + half)]


def quantile_interval(values: np.ndarray, q: float) -> dict:
    """The ``q`` quantile of ``values`` and its distribution-free 95 % interval: the order
    statistics whose ranks bracket it under the binomial law of the count below it."""
    x = np.sort(np.asarray(values, dtype=np.float64))
    n = len(x)
    if n == 0:
        return {"q": q, "value": math.nan, "ci95": [math.nan, math.nan]}
    lo = int(stats.binom.ppf(0.025, n, q))
    hi = int(stats.binom.ppf(0.975, n, q)) + 1
    return {"q": q, "value": float(np.quantile(x, q)),
            "ci95": [float(x[max(lo - 1, 0)]), float(x[min(hi - 1, n - 1)])]}


def compare(z_sim: np.ndarray, end_sim: np.ndarray, ticks_sim: np.ndarray,
            z_tab: np.ndarray, end_tab: np.ndarray, ticks_tab: np.ndarray,
            start: np.ndarray) -> dict:
    """The agreement of table outcomes with simulated ones, over those the simulator
    arrived in (module docstring); the position error also over the simulator's robots that
    left their ``start`` (the others bumped again where they were, which the table places
    exactly)."""
    arrived = z_sim >= 0
    n = int(arrived.sum())
    error = np.hypot(*(end_sim[arrived] - end_tab[arrived]).T)
    moved = np.hypot(*(end_sim[arrived] - start[arrived]).T) > 0
    gap = np.abs(ticks_sim[arrived] - ticks_tab[arrived])

    def share(mask: np.ndarray) -> dict:
        k = int(mask.sum())
        return {"share": k / n if n else math.nan, "ci95": wilson(k, n), "count": k}

    return {"n": n, "simulator_lost": int((~arrived).sum()),
            "same_state": share(z_sim[arrived] == z_tab[arrived]),
            "position_error": [quantile_interval(error, q) for q in QUANTILES],
            "moved": int(moved.sum()),
            "position_error_moved": [quantile_interval(error[moved], q) for q in QUANTILES],
            "ticks_exact": share(gap == 0), "ticks_within_1": share(gap <= 1)}


def table_error(table: BumpTable, model: CellModel, dynamics: dict, n: int = 1000,
                seed: int = 1, max_ticks: int | None = None) -> dict:
    """The table's error against the simulator on ``n`` held-out poses drawn with ``seed``
    (module docstring): ``bumps`` and ``reset`` (`compare`), and ``poses``, how many held-out
    bump poses there were."""
    rng = np.random.default_rng(seed)
    exact = dict(dynamics, noise=None)
    world, radius = dynamics["world"], float(dynamics.get("radius", 0.0))
    if max_ticks is None:
        max_ticks = default_max_ticks(dynamics)
    point = world.sample_free(rng, n, radius)
    heading = rng.uniform(0.0, 2 * math.pi, n)
    z, end, final, clock = reset_drives(model, exact, point, heading, rng, max_ticks)
    zt, endt, _, clockt = table.reset_drives(model, point, heading, max_ticks)
    reset = compare(z, end, clock, zt, endt, clockt, point)
    ok = np.flatnonzero(z >= 0)
    turn = rng.uniform(0.0, 2 * math.pi, len(ok))
    first = simulate_bumps(model, turn, np.arange(len(ok)), end[ok], final[ok], rng, exact,
                           max_ticks)
    held = np.flatnonzero(first.next_state >= 0)
    turn = rng.uniform(0.0, 2 * math.pi, len(held))
    action = np.arange(len(held))
    pose, pose_heading = first.end[held], first.heading[held]
    sim = simulate_bumps(model, turn, action, pose, pose_heading, rng, exact, max_ticks)
    tab = table.bumps(model, turn, action, pose, pose_heading, rng, None, max_ticks)
    bumps = compare(sim.next_state, sim.end, sim.ticks, tab.next_state, tab.end, tab.ticks,
                    pose)
    return {"poses": len(held), "bumps": bumps, "reset": reset}
