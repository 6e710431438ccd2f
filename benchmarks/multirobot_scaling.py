"""How `MultiBounceEnv` scales with the number of robots m at constant crowding.

Run with ``python -m benchmarks.multirobot_scaling`` (``--steps``, ``--repeats``, ``--ms``,
``--step-mode``, ``--unscaled``). Prints agent-steps/s (one agent-step = one robot's share of a parallel env step) at m = 20, 50,
100 on the kinematic and pymunk backends (both ``physics="ideal"``; ``step_mode="bounce"``,
``robot_collisions="bounce"``, robot radius 0.3, step length 1, random discrete actions), and
the ratio of the rate at the
largest m to the rate at m = 20 against the target 0.8: the cost per robot-step should not grow
with m. PettingZoo's ``pistonball_v6`` (20 pistons, random actions, no rendering) is measured in
the same run as the anchor when ``pettingzoo.butterfly`` imports. Asserts nothing.

The world: the ``grid_15x15`` layout with its cell size scaled by sqrt(m / 20), so the free area
grows in proportion to m. The robots are then as crowded at every m (free area per robot and the
chance per unit of distance to meet another robot are the same) and the world has the same edges,
so a wall ray cast costs the same; only the number of robots changes. (On the unscaled grid,
100 robots would be five times as crowded as 20: more contacts per step, a different workload;
``--unscaled`` measures that too.)
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import numpy as np

from bounce_gym import worlds
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.worlds.grid import world_from_grid

BASE_M = 20
TARGET = 0.8


def scaled_grid(m: int):
    """``grid_15x15`` with its cells scaled so that the free area per robot is that at m = 20."""
    free = worlds.get("grid_15x15").occupancy(1.0)
    return world_from_grid(free, math.sqrt(m / BASE_M), name=f"grid_15x15_x{m}")


def multi_env(m: int, backend: str, n_steps: int, step_mode: str = "bounce",
              world=None, physics: str = "ideal") -> Callable[[], int]:
    """A reset env and a function that runs ``n_steps`` parallel steps, returning agent-steps."""
    env = MultiBounceEnv(world=scaled_grid(m) if world is None else world, n_robots=m,
                         backend=backend, physics=physics, step_mode=step_mode,
                         max_cycles=10**9)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    n_actions = env.action_space(env.possible_agents[0]).n
    actions = [dict(zip(env.possible_agents, row.tolist(), strict=True))
               for row in rng.integers(0, n_actions, (n_steps, m))]

    def run() -> int:
        for a in actions:
            env.step(a)
        return n_steps * m

    return run


def pistonball(n_steps: int) -> Callable[[], int] | None:
    """20 pistons stepped with random actions, or None if pettingzoo.butterfly is missing."""
    try:
        from pettingzoo.butterfly import pistonball_v6
    except ImportError:  # needs pygame and pymunk
        return None
    env = pistonball_v6.parallel_env(n_pistons=20, continuous=False, max_cycles=10**9)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = [dict(zip(env.possible_agents, row.tolist(), strict=True))
               for row in rng.integers(0, 3, (n_steps, len(env.possible_agents)))]

    def run() -> int:
        for a in actions:
            env.step(a)
        return n_steps * len(env.possible_agents)

    return run


def rate(make: Callable[[], Callable[[], int] | None], repeats: int) -> float | None:
    """Best agent-steps/s over ``repeats`` runs, each on a freshly built and reset env."""
    best = None
    for _ in range(repeats):
        run = make()
        if run is None:
            return None
        start = time.perf_counter()
        n = run()
        r = n / (time.perf_counter() - start)
        best = r if best is None else max(best, r)
    return best


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000,
                        help="agent-steps per timed run (divided by m for env steps)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--ms", type=int, nargs="+", default=[20, 50, 100])
    parser.add_argument("--step-mode", choices=["bounce", "tick"], default="bounce")
    parser.add_argument("--unscaled", action="store_true",
                        help="the plain grid_15x15 at every m (crowding grows with m)")
    args = parser.parse_args(argv)
    world = (lambda m: worlds.get("grid_15x15")) if args.unscaled else scaled_grid
    anchor = rate(lambda: pistonball(max(args.steps // 20, 1)), args.repeats)
    print(f"{'backend':<10} {'m':>4} {'world':<16} {'agent-steps/s':>14} {'x pistonball':>13}")
    if anchor is not None:
        print(f"{'pistonball':<10} {20:>4} {'pistonball_v6':<16} {anchor:>14,.0f} {1.0:>13.2f}")
    for backend in ("kinematic", "pymunk"):
        rates = {}
        for m in args.ms:
            rates[m] = rate(lambda m=m, b=backend: multi_env(m, b, max(args.steps // m, 1),
                                                             args.step_mode, world(m)),
                            args.repeats)
            rel = f"{rates[m] / anchor:13.2f}" if anchor else f"{'—':>13}"
            print(f"{backend:<10} {m:>4} {world(m).name:<16} {rates[m]:>14,.0f} {rel}")
        lo, hi = min(args.ms), max(args.ms)
        print(f"{backend:<10} ratio m={hi} / m={lo}: {rates[hi] / rates[lo]:.2f} "
              f"(target >= {TARGET}; {args.step_mode} mode)")


if __name__ == "__main__":
    main()
