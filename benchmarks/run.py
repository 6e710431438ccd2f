"""Speed of the simulator core: bounces per second per backend, world and robot count.

Run with ``make bench`` (or ``python -m benchmarks.run``). Prints a table; asserts nothing.
Each row is the best of ``--repeats`` timed runs on one process (one core).

Rows (issue #2): one robot and 1024 independent robots on the kinematic backend, one robot and
20 colliding robots on the pymunk backend, in ``two_rooms`` and ``grid_15x15``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics


def _time(setup: Callable[[], Callable[[], int]], repeats: int) -> float:
    """Best rate (events per second) of ``repeats`` runs; ``setup`` returns the timed callable."""
    best = 0.0
    for _ in range(repeats):
        run = setup()
        start = time.perf_counter()
        events = run()
        best = max(best, events / (time.perf_counter() - start))
    return best


def single_robot(world, backend: str, n_bounces: int) -> Callable[[], int]:
    dyn = BounceDynamics(world, 1, backend=backend, radius=0.0)
    dyn.reset(np.random.default_rng(0))
    dyn.drive_to_contact()
    angles = np.random.default_rng(1).uniform(0.2, 2 * np.pi - 0.2, n_bounces)

    def run() -> int:
        for a in angles:
            dyn.bounce(a)
        return n_bounces

    return run


def independent_robots(world, n_robots: int, n_rounds: int) -> Callable[[], int]:
    dyn = BounceDynamics(world, n_robots, backend="kinematic", robot_collisions="ignore")
    dyn.reset(np.random.default_rng(0))
    dyn.bounce_each(1.0)  # nobody is blocked yet: drive to the first contact
    angles = np.random.default_rng(1).uniform(0.2, 2 * np.pi - 0.2, (n_rounds, n_robots))

    def run() -> int:
        for row in angles:
            dyn.bounce_each(row)
        return n_rounds * n_robots

    return run


def colliding_robots(world, backend: str, n_robots: int, n_steps: int) -> Callable[[], int]:
    dyn = BounceDynamics(world, n_robots, backend=backend, radius=0.3, robot_collisions="bounce")
    dyn.reset(np.random.default_rng(0))
    dyn.drive_to_contact()
    angles = np.random.default_rng(1).uniform(0.2, 2 * np.pi - 0.2, (n_steps, n_robots))

    def run() -> int:
        before = int(dyn.state.bumps.sum())
        for row in angles:
            dyn.bounce(row)
        return int(dyn.state.bumps.sum()) - before  # robot-bounces, not env steps

    return run


def rows(quick: bool) -> list[tuple[str, str, str, Callable[[], Callable[[], int]]]]:
    scale = 0.2 if quick else 1.0
    n1 = int(20_000 * scale)
    out = []
    for name in ("two_rooms", "grid_15x15"):
        world = worlds.get(name)
        out += [
            (name, "kinematic", "1 robot", lambda w=world: single_robot(w, "kinematic", n1)),
            (name, "kinematic", "1024 independent",
             lambda w=world: independent_robots(w, 1024, int(300 * scale))),
            (name, "pymunk", "1 robot", lambda w=world: single_robot(w, "pymunk", n1 // 2)),
            (name, "pymunk", "20 colliding (r=0.3)",
             lambda w=world: colliding_robots(w, "pymunk", 20, int(1000 * scale))),
            (name, "kinematic", "20 colliding (r=0.3)",
             lambda w=world: colliding_robots(w, "kinematic", 20, int(1000 * scale))),
        ]
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer bounces per row")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(f"{'world':<12} {'backend':<10} {'robots':<22} {'robot-bounces/s':>16}")
    for world, backend, robots, setup in rows(args.quick):
        rate = _time(setup, args.repeats)
        print(f"{world:<12} {backend:<10} {robots:<22} {rate:>16,.0f}", flush=True)


if __name__ == "__main__":
    main()
