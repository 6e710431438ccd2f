"""Speed and memory of the analytic planners: the bounce visibility graph and all navigation plans.

Run with ``python -m benchmarks.planners`` (``--quick`` skips the 12,480-cell map). Prints rows;
asserts nothing. Rates are the best of ``--repeats`` runs (time.perf_counter); memory is the
peak that tracemalloc sees (numpy's arrays included) while the call runs.

* ``two_rooms``: partition (Alg. 1) + G_safe per second, the anchor; partition + G_safe + the
  bounce visibility graph (`baselines.visibility.graph.bvg`) per second; their ratio (target
  ≥ 1/20). One World throughout: its grown free-space region is built once and cached.
* `Roadmap.all_pairs` (Φ = {45°, 90°, 135°}, w1 = 1, w2 = 100) and its plan histogram on
  ``lab_complex`` × 8 bins (1,464 cells) and on a generated 40 × 40 grid with 10 obstacles
  (``random_grid(default_rng(0), 40, 40, 10, 3)``) × 8 bins (12,480 cells): time and peak memory.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from collections.abc import Callable

import numpy as np

from baselines.navigation import Roadmap
from baselines.visibility.graph import bvg, safe_graph
from baselines.visibility.partition import partition
from bounce_gym.cells import CellModel
from bounce_gym.worlds import World, get
from bounce_gym.worlds.generators import random_grid

PHI = (45, 90, 135)


def visibility_round(world: World, with_bvg: bool, rounds: int) -> Callable[[], int]:
    """A timed callable: ``rounds`` times partition + G_safe (+ BVG) of ``world``."""

    def run() -> int:
        for _ in range(rounds):
            part = partition(world)
            safe_graph(part)
            if with_bvg:
                bvg(part)
        return rounds

    return lambda: run


def all_pairs_cost(model: CellModel) -> dict:
    """Seconds and peak bytes of `Roadmap.all_pairs`, then of its histogram."""
    roadmap = Roadmap(model, PHI, w1=1.0, w2=100.0)
    tracemalloc.start()
    start = time.perf_counter()
    plans = roadmap.all_pairs()
    seconds = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.reset_peak()
    start = time.perf_counter()
    hist = plans.histogram()
    hist_seconds = time.perf_counter() - start
    hist_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return dict(cells=model.n_cells, seconds=seconds, peak=peak, hist_seconds=hist_seconds,
                hist_peak=hist_peak, kept_trees=min(plans.capacity, model.n_cells), histogram=hist)


def main(quick: bool = False, repeats: int = 3) -> dict:
    from benchmarks.run import _time as _best_rate  # imported here: run.py may import this module

    world = get("two_rooms")
    rounds = 5 if quick else 20
    anchor = _best_rate(visibility_round(world, False, rounds), repeats)
    full = _best_rate(visibility_round(world, True, rounds), repeats)
    ratio = full / anchor
    verdict = "ok" if ratio >= 1 / 20 else "below target"
    print(f"two_rooms partition + G_safe: {anchor:,.1f}/s; partition + G_safe + BVG: "
          f"{full:,.1f}/s")
    print(f"{'(partition + G_safe + BVG) / (partition + G_safe)':<58} 1/{1 / ratio:>6.1f}  "
          f"target >= 1/20  {verdict}")
    maps = [("lab_complex x 8 bins", CellModel(get("lab_complex"), n_bins=8))]
    if not quick:
        grid = random_grid(np.random.default_rng(0), 40, 40, 10, 3)
        maps.append(("40x40 random grid x 8 bins", CellModel(grid, n_bins=8)))
    rows = []
    for name, model in maps:
        row = all_pairs_cost(model)
        rows.append(row)
        print(f"all pairs, {name} ({row['cells']:,} cells): {row['seconds']:.2f} s, peak "
              f"{row['peak'] / 2**20:,.0f} MiB ({row['kept_trees']:,} trees kept); histogram "
              f"{row['hist_seconds']:.2f} s, peak {row['hist_peak'] / 2**20:,.0f} MiB")
    return dict(anchor=anchor, with_bvg=full, ratio=ratio, all_pairs=rows)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    main(args.quick, args.repeats)
