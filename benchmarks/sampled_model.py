"""Building the sampled generalized cell mapping (issue 24): seconds per model, and its sample
rate against the raw simulator measured in the same run.

Run with ``python -m benchmarks.sampled_model [--rounds R] [--quick]`` (part of ``make bench``).
Two maps, kinematic backend, Φ = {45°, 90°, 135°}, decision cells of the robot's step, no cache
(`bounce_gym.dynamics.sampled_model.sampled_model` with ``cache=False``):

* ``lab_navigation`` (the navigation lab map), 50 samples per decision state and angle;
* a 100 × 100 generated grid map (10⁴ cells, `bounce_gym.worlds.generators.random_grid`, seed
  0, 150 obstacles of up to 6 × 6 cells), 5 samples per decision state and angle (its ~10⁴
  decision states take minutes at more).

Anchor: the kinematic backend bouncing 1,024 independent robots (`BounceDynamics.bounce_each`)
in the same world, bounces per second. The ratio is the sampler's simulated bounces per second
(sample points × the rounds of re-sampling, `sample_outcomes`) ÷ the anchor's: what the
bookkeeping around the simulator costs. Each figure is the median (min–max) over ``--rounds``
rounds, with the load average before and after. One process, one core. Asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from bounce_gym import worlds
from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.bump_sampler import ROUNDS
from bounce_gym.dynamics.sampled_model import sampled_model
from bounce_gym.worlds.generators import random_grid

ANGLES = np.radians([45.0, 90.0, 135.0])


MAPS = ("lab_navigation", "grid_100x100")


def _maps(quick: bool, names: list[str]) -> list[tuple[str, worlds.World, int]]:
    out = []
    if "lab_navigation" in names:
        out.append(("lab_navigation", worlds.get("lab_navigation"), 20 if quick else 50))
    if "grid_100x100" in names:
        grid = random_grid(np.random.default_rng(0), 100, 100, 150, 6, name="grid_100x100")
        out.append(("grid_100x100", grid, 2 if quick else 5))
    return out


def _build(world, samples: int) -> tuple[float, int, int]:
    """Seconds to build the model, its decision states and its sample points."""
    model = CellModel(world, 1.0, 8)
    dynamics = {"world": world, "backend": "kinematic", "radius": 0.0, "step_length": 1.0}
    start = time.perf_counter()
    built = sampled_model(model, dynamics, ANGLES, samples=samples, seed=0, cache=False)
    seconds = time.perf_counter() - start
    return seconds, len(built.outcomes.states), len(built.outcomes.state)


def _anchor(world, n_rounds: int = 20) -> float:
    """Bounces per second of 1,024 independent kinematic robots in ``world``."""
    dyn = BounceDynamics(world, 1024, backend="kinematic", robot_collisions="ignore")
    dyn.reset(np.random.default_rng(0))
    dyn.bounce_each(1.0)
    angles = np.random.default_rng(1).uniform(0.2, 2 * math.pi - 0.2, (n_rounds, 1024))
    start = time.perf_counter()
    for row in angles:
        dyn.bounce_each(row)
    return n_rounds * 1024 / (time.perf_counter() - start)


def _spread(values: list[float]) -> str:
    return f"{np.median(values):.3g} ({min(values):.3g}–{max(values):.3g})"


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="fewer samples")
    parser.add_argument("--maps", nargs="+", choices=MAPS, default=list(MAPS))
    args = parser.parse_args(argv)
    print("\nBuilding the sampled GCM (kinematic, Φ = {45°, 90°, 135°}, no cache; median (min–max) "
          f"over {args.rounds} rounds)")
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    out = {}
    for name, world, samples in _maps(args.quick, args.maps):
        seconds, ratios = [], []
        for _ in range(args.rounds):
            took, states, points = _build(world, samples)
            anchor = _anchor(world)
            seconds.append(took)
            ratios.append(points * (ROUNDS + 1) / took / anchor)
        out[name] = {"seconds": seconds, "ratio": ratios, "states": states, "points": points}
        print(f"{name:16s} {samples:3d} samples/state/angle  {states:6d} states  "
              f"{points:8d} points  build {_spread(seconds)} s  "
              f"sampler ÷ raw kinematic bounces {_spread(ratios)}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return out


if __name__ == "__main__":
    main()
