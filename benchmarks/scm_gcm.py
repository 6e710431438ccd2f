"""Scale of the cell-mapping analyses (issue #4).

Run with ``python -m benchmarks.scm_gcm``. Prints one row per measurement; asserts nothing.

* SCM at the localization paper's simulation scale (Alam, Bobadilla & Shell
  2018, Sec. V-A): a 200 x 125 grid world with a
  few rectangular obstacles at 1° bins (360 orientations, about 9 M cells). Reports the time to
  build the successor array (`CellModel` + ``successor``), the time of `simple_cell_mapping`,
  the peak traced memory of the analysis (tracemalloc; numpy reports its buffers to it) and the
  peak resident memory of the whole process (``ru_maxrss``). Targets: <= 60 s, <= 4 GiB.
* GCM on ``lab_complex`` at 360 bins (65 880 cells), φ = 30°, ε = 5°, r = 0.8: persistent
  groups, stationary distributions and the limiting distribution (docs/choices/navigation_coverage.md, "The limiting
  distribution starts anywhere"), from the
  transition matrix. Target: <= 2 s. The matrix build and the lazy absorption matrix are timed
  on their own rows.
"""

from __future__ import annotations

import argparse
import math
import resource
import sys
import time
import tracemalloc

import numpy as np

from bounce_gym.cells import CellModel
from bounce_gym.markov.gcm import generalized_cell_mapping
from bounce_gym.markov.scm import simple_cell_mapping
from bounce_gym.worlds import get, world_from_grid

GIB = 1024**3

#: Obstacles of the large world: (row0, row1, col0, col1), half-open, rows from the bottom.
OBSTACLES = ((20, 35, 30, 45), (70, 85, 120, 140), (50, 54, 80, 120), (0, 10, 185, 200),
             (110, 125, 10, 20))


def large_world(rows: int = 125, cols: int = 200):
    free = np.ones((rows, cols), dtype=bool)
    for r0, r1, c0, c1 in OBSTACLES:
        free[r0:r1, c0:c1] = False
    return world_from_grid(free, name=f"bench_{cols}x{rows}")


def _peak_rss() -> float:
    """Peak resident set size of this process so far, in bytes."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return float(peak if sys.platform == "darwin" else peak * 1024)


def _row(name: str, value: str, target: str = "") -> None:
    print(f"{name:<48} {value:>16}  {target}")


def bench_scm(n_bins: int = 360, phi_deg: float = 45.0) -> None:
    start = time.perf_counter()
    world = large_world()
    world_time = time.perf_counter() - start
    start = time.perf_counter()
    model = CellModel(world, n_bins=n_bins)
    succ, _ = model.successor(math.radians(phi_deg))
    build_time = time.perf_counter() - start
    del _
    tracemalloc.start()
    start = time.perf_counter()
    res = simple_cell_mapping(succ)
    scm_time = time.perf_counter() - start
    _, traced = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    label = f"SCM 200x125 ({model.n_positions} pos x {n_bins} bins, φ={phi_deg:g}°)"
    print(label)
    _row("  cells N", f"{model.n_cells:,}")
    _row("  world_from_grid [s]", f"{world_time:.2f}")
    _row("  CellModel + successor [s]", f"{build_time:.2f}")
    _row("  simple_cell_mapping [s]", f"{scm_time:.2f}", "(target <= 60 s)")
    _row("  analysis peak traced memory [GiB]", f"{traced / GIB:.3f}")
    _row("  process peak RSS [GiB]", f"{_peak_rss() / GIB:.3f}", "(target <= 4 GiB)")
    _row("  periodic groups r", f"{res.n_groups}")
    _row("  periodic cells", f"{int(res.periodic.sum()):,}")
    _row("  max period / max transient", f"{int(res.periods.max())} / {res.max_transient}")


def bench_gcm(repeats: int = 3) -> None:
    model = CellModel(get("lab_complex"), n_bins=360)
    phi, eps, r = math.radians(30), math.radians(5), 0.8
    start = time.perf_counter()
    P = model.transition_matrix(phi, eps, r)
    build_time = time.perf_counter() - start
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        res = generalized_cell_mapping(P)
        best = min(best, time.perf_counter() - start)
    start = time.perf_counter()
    a = res.absorption
    abs_time = time.perf_counter() - start
    print(f"GCM lab_complex ({model.n_cells:,} cells), φ=30°, ε=5°, r=0.8")
    _row("  transition_matrix [s]", f"{build_time:.3f}")
    _row("  groups + stationary + limiting [s]", f"{best:.3f}", "(target <= 2 s; best of "
         f"{repeats})")
    _row("  absorption matrix (lazy) [s]", f"{abs_time:.3f}", f"({a.shape[0]} x {a.shape[1]})")
    _row("  persistent groups (sizes)", " ".join(str(s) for s in res.sizes))
    _row("  transient cells", f"{len(res.transient):,}")
    _row("  weights w_g", " ".join(f"{w:.4f}" for w in res.weights))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-scm", action="store_true", help="skip the 9 M-cell SCM rows")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    bench_gcm(args.repeats)
    if not args.skip_scm:
        bench_scm()


if __name__ == "__main__":
    main()
