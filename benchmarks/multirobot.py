"""Multi-robot coverage with bouncing robots (Alam & Bobadilla 2020, §5.1, Figs. 7–9).

Run with ``python -m benchmarks.multirobot`` (``--seeds``, ``--max-steps``, ``--neighbors``,
``--large-seeds``, ``--timing-seeds``). Prints tables; asserts nothing.

* Steps to complete coverage (Algorithm 1, φ = 135° for every robot, 8 headings, corner rule
  ``no_squeeze``, rotation neighbours) against m = 2..5 on ``grid_10x10`` and ``grid_15x15``: mean
  ± std over ``--seeds`` random initial joint cells (distinct free cells, uniform headings; seed
  s = 0..seeds−1), with the robot–robot collisions up to full coverage, the number of neighbour
  jumps and the runs that did not finish within ``--max-steps``. Paper (layouts unpublished, so
  only qualitative): ~10³ steps on 10×10 falling with m; ~10⁴ on 15×15 with m = 5 above m = 4.
* Coverage reached by m = 10 on ``grid_20x12`` within ``--max-steps`` (paper: 98 %).
* Algorithm 1 planning cost against m = 2..10 on ``grid_15x15`` (issue: "coverage planning for
  m = 2…10"): mean wall time of `plan_coverage` (``stop_at_full=True``, same settings as above)
  over ``--timing-seeds`` seeds, mean steps to full coverage (or the coverage reached), and the
  peak memory traced by `tracemalloc` in a second, separate run of each seed (tracing slows the
  planner ~5×, so it is kept out of the timed run).
Coverage is over the free position cells reachable from the start cells.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from baselines.multirobot import plan_coverage, random_start
from bounce_gym import worlds
from bounce_gym.cells import CellModel, JointCellModel


def _mean_std(values) -> str:
    v = np.asarray(values, dtype=float)
    if len(v) == 0:
        return "—"
    return f"{v.mean():8.1f} ± {v.std():7.1f}"


def steps_table(world: str, ms, seeds: int, max_steps: int, neighbors: str) -> None:
    model = CellModel(worlds.get(world), corner_rule="no_squeeze")
    print(f"\n{world}: {model.n_positions} free cells, φ = 135°, {seeds} seeds, "
          f"neighbours = {neighbors}, max_steps = {max_steps}")
    print(f"{'m':>3} | {'steps to full (mean ± std)':>27} | {'min':>6} | {'max':>6} | "
          f"{'collisions':>19} | {'jumps':>15} | {'unfinished':>10} | {'time s':>6}")
    for m in ms:
        jm = JointCellModel(model, [135.0] * m)
        steps, coll, jumps, unfinished = [], [], [], 0
        start = time.perf_counter()
        for seed in range(seeds):
            res = plan_coverage(jm, random_start(jm, seed), max_steps=max_steps,
                                neighbors=neighbors, stop_at_full=True)
            if res.steps_to_full is None:
                unfinished += 1
                continue
            steps.append(res.steps_to_full)
            coll.append(res.collisions_to_full)
            jumps.append(len(res.jumps))
        elapsed = time.perf_counter() - start
        lo = min(steps) if steps else "—"
        hi = max(steps) if steps else "—"
        print(f"{m:>3} | {_mean_std(steps):>27} | {lo:>6} | {hi:>6} | {_mean_std(coll):>19} | "
              f"{_mean_std(jumps):>15} | {unfinished:>10} | {elapsed:6.1f}")


def large_map(seeds: int, max_steps: int, neighbors: str, m: int = 10) -> None:
    model = CellModel(worlds.get("grid_20x12"), corner_rule="no_squeeze")
    jm = JointCellModel(model, [135.0] * m)
    print(f"\ngrid_20x12: {model.n_positions} free cells, m = {m}, φ = 135°, {seeds} seeds, "
          f"max_steps = {max_steps} (paper: 98 %)")
    print(f"{'seed':>4} | {'coverage %':>10} | {'of all free %':>13} | {'steps to full':>13} | "
          f"{'steps run':>9} | {'collisions':>10}")
    covs = []
    for seed in range(seeds):
        res = plan_coverage(jm, random_start(jm, seed), max_steps=max_steps, neighbors=neighbors,
                            stop_at_full=True)
        covs.append(100 * res.final_coverage)
        full = res.steps_to_full if res.steps_to_full is not None else "—"
        print(f"{seed:>4} | {covs[-1]:10.1f} | {100 * res.coverage_all[-1]:13.1f} | {full:>13} | "
              f"{len(res.trajectory) - 1:>9} | {res.collisions:>10}")
    print(f"mean coverage {np.mean(covs):.1f} ± {np.std(covs):.1f} %")


def planning_cost(seeds: int, max_steps: int, neighbors: str, ms=range(2, 11)) -> None:
    """Algorithm 1's planning time, steps and peak traced memory against m on grid_15x15."""
    model = CellModel(worlds.get("grid_15x15"), corner_rule="no_squeeze")
    print(f"\nplanning cost, grid_15x15: {model.n_positions} free cells, φ = 135°, {seeds} seeds, "
          f"neighbours = {neighbors}, max_steps = {max_steps}")
    print(f"{'m':>3} | {'plan s (mean)':>13} | {'steps to full (mean)':>20} | "
          f"{'coverage % (mean)':>17} | {'unfinished':>10} | {'peak traced MiB':>15}")
    for m in ms:
        jm = JointCellModel(model, [135.0] * m)
        starts = [random_start(jm, seed) for seed in range(seeds)]
        times, steps, covs = [], [], []
        for x0 in starts:
            start = time.perf_counter()
            res = plan_coverage(jm, x0, max_steps=max_steps, neighbors=neighbors,
                                stop_at_full=True)
            times.append(time.perf_counter() - start)
            covs.append(100 * res.final_coverage)
            if res.steps_to_full is not None:
                steps.append(res.steps_to_full)
        peak = 0
        for x0 in starts:
            tracemalloc.start()
            plan_coverage(jm, x0, max_steps=max_steps, neighbors=neighbors, stop_at_full=True)
            peak = max(peak, tracemalloc.get_traced_memory()[1])
            tracemalloc.stop()
        mean_steps = f"{np.mean(steps):20.0f}" if steps else f"{'—':>20}"
        print(f"{m:>3} | {np.mean(times):13.3f} | {mean_steps} | {np.mean(covs):17.1f} | "
              f"{seeds - len(steps):>10} | {peak / 2**20:15.1f}", flush=True)


def monitoring_enumeration() -> None:
    """Algorithm 2's joint map for m = 2 on grid_15x15: every joint cell, time and memory."""
    import resource

    import numpy as np

    from baselines.multirobot.monitoring import joint_monitoring_cycles
    from bounce_gym import worlds
    from bounce_gym.cells import CellModel

    model = CellModel(worlds.get("grid_15x15"), n_bins=8)
    print(f"\nmonitoring, m = 2, grid_15x15: {model.n_cells ** 2 + 1:,} joint cells (with the sink)")
    for phi in (45, 90, 135):
        start = time.perf_counter()
        result = joint_monitoring_cycles(model, [np.radians(phi)] * 2)
        elapsed = time.perf_counter() - start
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
        print(f"  φ = {phi:>3}°: {elapsed:.2f} s, peak RSS {rss:.2f} GiB, accepted groups "
              f"r = {result.r}, periods {sorted({int(p) for p in result.periods})[:8]}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--max-steps", type=int, default=100_000)
    parser.add_argument("--neighbors", choices=("rotation", "full"), default="rotation")
    parser.add_argument("--large-seeds", type=int, default=5)
    parser.add_argument("--timing-seeds", type=int, default=3,
                        help="seeds per m in the m = 2..10 planning-cost table")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    for world in ("grid_10x10", "grid_15x15"):
        steps_table(world, (2, 3, 4, 5), args.seeds, args.max_steps, args.neighbors)
    large_map(args.large_seeds, 10_000, args.neighbors)
    planning_cost(args.timing_seeds, args.max_steps, args.neighbors)
    monitoring_enumeration()
    print(f"\ntotal {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
