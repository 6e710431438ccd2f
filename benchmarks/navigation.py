"""Scale of the navigation planner (issue #5): roadmap, single queries, all plans.

Run with ``python -m benchmarks.navigation``. Prints one block per map; asserts nothing.

For ``lab_complex`` (183 positions x 8 bins = 1464 cells, the paper's "complex" environment of Sec.
V-C) and ``lab_navigation`` (48 x 8 = 384 cells, the reconstruction of the Sec. V-A lab), Φ = {45°,
90°, 135°}, w1 = 1, w2 = 100 (Alam, Bobadilla & Shell 2017, Secs. IV–V):

* building the layered roadmap (`baselines.navigation.Roadmap`);
* a single query (Alg. 1: one Dijkstra from all layers of the start, plus decoding), the mean
  over random (start, goal) pairs;
* all plans (Alg. 2 with line 12 fixed: N single-source Dijkstra runs keeping L and the
  predecessor trees; best of ``--repeats``), and the plan-count histogram by number of distinct
  angles (the paper's Figs. 7-8 statistic) with its time.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from baselines.navigation import Roadmap
from bounce_gym.cells import CellModel
from bounce_gym.worlds import get

PHI = (45, 90, 135)


def _row(name: str, value: str, note: str = "") -> None:
    print(f"{name:<44} {value:>16}  {note}")


def bench_map(name: str, repeats: int = 3, queries: int = 200, seed: int = 0) -> dict:
    """Time the planner on one zoo map; returns the measurements."""
    model = CellModel(get(name), n_bins=8)
    start = time.perf_counter()
    roadmap = Roadmap(model, PHI, w1=1.0, w2=100.0)
    build = time.perf_counter() - start

    rng = np.random.default_rng(seed)
    pairs = rng.integers(model.n_cells, size=(queries, 2)).tolist()
    start = time.perf_counter()
    found = sum(roadmap.plan(i, j) is not None for i, j in pairs)
    single = (time.perf_counter() - start) / queries

    best = np.inf
    for _ in range(repeats):
        fresh = Roadmap(model, PHI, w1=1.0, w2=100.0)
        start = time.perf_counter()
        plans = fresh.all_pairs()
        best = min(best, time.perf_counter() - start)
    start = time.perf_counter()
    hist = plans.histogram()
    hist_time = time.perf_counter() - start
    start = time.perf_counter()
    for i, j in pairs:
        plans.plan_between(i, j)
    decode = (time.perf_counter() - start) / queries

    print(f"{name}: {model.n_positions} positions x 8 bins = {model.n_cells} cells, "
          f"Φ = {list(PHI)}°, w1 = 1, w2 = 100")
    _row("  roadmap nodes / edges", f"{roadmap.n_nodes} / {roadmap.graph.nnz}")
    _row("  build roadmap [ms]", f"{build * 1e3:.2f}")
    _row("  single query (Dijkstra + decode) [ms]", f"{single * 1e3:.3f}",
         f"(mean of {queries}, {found} with a plan)")
    _row("  all pairs, N Dijkstras [s]", f"{best:.3f}",
         f"(best of {repeats}; {fresh.dijkstra_calls} calls)")
    _row("  decode one stored plan [ms]", f"{decode * 1e3:.3f}")
    _row("  histogram of distinct angles [s]", f"{hist_time:.3f}")
    _row("  plans by distinct angles 0/1/2/3",
         f"{hist[0]}/{hist[1]}/{hist[2]}/{hist[3]}", f"(unreachable pairs: {hist['none']})")
    return {"map": name, "cells": model.n_cells, "build": build, "single": single,
            "all_pairs": best, "histogram": hist}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--queries", type=int, default=200)
    args = parser.parse_args(argv)
    for name in ("lab_complex", "lab_navigation"):
        bench_map(name, repeats=args.repeats, queries=args.queries)


if __name__ == "__main__":
    main()
