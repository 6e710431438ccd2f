"""The tabulated bump-to-bump map of ``physics="dynamic"`` (`bounce_gym.dynamics.bump_table`):
a particle update from the table against the simulator in the same run, the table's build time
and size, and its prediction error against the simulator on held-out poses.

Run with ``python -m benchmarks.bump_table [--maps ...] [--rounds R] [--quick]``. Per map
(default: the two lab maps of the localization and navigation envs and the generated
``configs/maps/bench_grid_14x22.yaml``), pymunk's dynamic physics (Create 2, step length 1),
Φ = {45°, 135°}, noise ``reliable`` (r = 0.8, ε = 5°):

* **update**: seconds to move ``--particles`` particles (default 10,000) one bump, through the
  table (`BumpMotion.bumps`) and — the anchor, in the same run, on the same particles — through
  the simulator (`bump_sampler.simulate_bumps`); the ratio is simulator ÷ table. Each figure is
  the median (min–max) over ``--rounds`` rounds (at least 3), with the load average before and
  after. One process, one core.
* **build**: seconds to tabulate (from a fresh cache folder, once per map), nodes and megabytes.
* **error**: `bounce_gym.dynamics.table_check.table_error` on ``--poses`` held-out poses.

Asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from bounce_gym import worlds
from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics.bump_sampler import reset_drives, simulate_bumps
from bounce_gym.dynamics.bump_table import (
    DEFAULT_HEADINGS,
    DEFAULT_SPACING,
    BumpMotion,
    bump_table,
)
from bounce_gym.dynamics.table_check import table_error
from bounce_gym.worlds.io import load

ANGLES = np.radians([45.0, 135.0])
NOISE = {"type": "reliable", "r": 0.8, "eps_deg": 5}
RADIUS = 0.17
GRID_MAP = Path(__file__).parents[1] / "configs" / "maps" / "bench_grid_14x22.yaml"
MAPS = ("lab_localization_a", "lab_navigation", "bench_grid_14x22")


def _world(name: str) -> worlds.World:
    return load(GRID_MAP) if name == "bench_grid_14x22" else worlds.get(name)


def _spread(values: list[float]) -> str:
    return f"{np.median(values):.3g} ({min(values):.3g}–{max(values):.3g})"


def _particles(model: CellModel, dynamics: dict, n: int, seed: int
               ) -> tuple[np.ndarray, np.ndarray]:
    """``n`` bump poses produced by the simulator: reset drives from random free poses."""
    rng = np.random.default_rng(seed)
    world = dynamics["world"]
    z, end, heading, _ = reset_drives(model, dynamics, world.sample_free(rng, n, RADIUS),
                                      rng.uniform(0, 2 * math.pi, n), rng, 200)
    keep = np.flatnonzero(z >= 0)
    pick = keep[rng.integers(0, len(keep), n)]
    return end[pick], heading[pick]


def bench_map(name: str, particles: int, rounds: int, poses: int, spacing: float,
              headings: int, cache: Path) -> dict:
    """Update, build and error figures of one map (module docstring)."""
    world = _world(name)
    dynamics = {"world": world, "backend": "pymunk", "radius": RADIUS, "step_length": 1.0,
                "physics": "dynamic", "noise": NOISE}
    model = CellModel(world, 1.0, 8, robot_radius=RADIUS)
    began = time.perf_counter()
    table = bump_table(dynamics, spacing, headings, cache=cache)
    took = time.perf_counter() - began
    motion = BumpMotion(model, dynamics, table)
    point, heading = _particles(model, dynamics, particles, 0)
    action = np.random.default_rng(1).integers(0, len(ANGLES), particles)
    fast, slow = [], []
    for r in range(rounds):
        start = time.perf_counter()
        motion.bumps(ANGLES, action, point, heading, np.random.default_rng(r), 200)
        fast.append(time.perf_counter() - start)
        start = time.perf_counter()
        simulate_bumps(model, ANGLES, action, point, heading, np.random.default_rng(r),
                       dynamics, 200)
        slow.append(time.perf_counter() - start)
    error = table_error(table, model, dynamics, n=poses, seed=11)
    return {"table_seconds": fast, "simulator_seconds": slow,
            "ratio": [s / f for s, f in zip(slow, fast, strict=True)],
            "build_seconds": table.build_seconds, "load_or_build_seconds": took,
            "nodes": table.n_nodes, "megabytes": table.nbytes / 1e6, "error": error}


def _share(row: dict) -> str:
    lo, hi = row["ci95"]
    return f"{100 * row['share']:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]"


def _report(name: str, out: dict, particles: int) -> None:
    print(f"{name}: {out['nodes']} nodes, {out['megabytes']:.1f} MB, built in "
          f"{out['build_seconds']:.0f} s")
    print(f"  update of {particles} particles: table {_spread(out['table_seconds'])} s, "
          f"simulator {_spread(out['simulator_seconds'])} s, simulator ÷ table "
          f"{_spread(out['ratio'])}")
    for kind in ("bumps", "reset"):
        e = out["error"][kind]
        print(f"  {kind} (n = {e['n']}): same state {_share(e['same_state'])}, clock exact "
              f"{_share(e['ticks_exact'])}, within 1 {_share(e['ticks_within_1'])}")
        for label, key in (("all", "position_error"),
                           (f"{e['moved']} that moved", "position_error_moved")):
            quantiles = ", ".join(f"{int(100 * q['q'])} % {1000 * q['value']:.2g} mm "
                                  f"[{1000 * q['ci95'][0]:.2g}, {1000 * q['ci95'][1]:.2g}]"
                                  for q in e[key])
            print(f"    position error, {label}: {quantiles}")


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="+", default=list(MAPS),
                        help="zoo names or bench_grid_14x22")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--particles", type=int, default=10_000)
    parser.add_argument("--poses", type=int, default=1000, help="held-out poses of the error")
    parser.add_argument("--spacing", type=float, default=DEFAULT_SPACING)
    parser.add_argument("--headings", type=int, default=DEFAULT_HEADINGS)
    parser.add_argument("--cache", default=None,
                        help="a folder of built tables (default: a fresh one: build times)")
    parser.add_argument("--quick", action="store_true", help="1,000 particles, 200 poses")
    args = parser.parse_args(argv)
    particles, poses = (1000, 200) if args.quick else (args.particles, args.poses)
    rounds = max(args.rounds, 3)
    print(f"\nTabulated bump map, pymunk dynamic physics (median (min–max) over {rounds} rounds)")
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    out = {}
    with tempfile.TemporaryDirectory() as fresh:
        cache = Path(args.cache) if args.cache else Path(fresh)
        for name in args.maps:
            out[name] = bench_map(name, particles, rounds, poses, args.spacing, args.headings,
                                  cache)
            _report(name, out[name], particles)
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return out


if __name__ == "__main__":
    main()
