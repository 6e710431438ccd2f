"""Closed-loop planners on pymunk's dynamic physics: seconds per planner episode, one core.

Run with ``python -m benchmarks.physics_planners [--episodes N] [--rounds R] [--rows WORD ...]``. Rotation noise
``reliable`` (r = 0.9, ε = 5°), held-out seeds from 10,000, the planners' particles and searches
reading the tabulated bump map (`bounce_gym.dynamics.bump_table`; its build is timed apart, from
the cache folder it is in):

* **navigation**: the search planner (Φ = {45°, 90°, 135°}) on the lab map and on the generated
  ``configs/maps/bench_grid_14x22.yaml``, and the continuous-angle planner on the lab map
  (BounceNavigation-v0, goal radius 0.3, heading tolerance 10°, 200 steps);
* **localization**: `ParticleLocalizationPolicy` with 10,000 particles of its own on the lab map
  (BounceLocalization-v0, Φ = {45°, 135°}), ``--bumps`` bumps per episode (the env's claim
  filter off: only the planner's cost is timed).

A planner's time is that of its ``reset`` and ``act`` calls (not the env's steps). Per row the
median, 90th percentile and maximum over the episodes, and per round the median, so that the
spread over ``--rounds`` rounds (at least 3) shows. The anchor, in the same run: one update of
10,000 particles through the simulator itself (`bump_sampler.simulate_bumps`), the cost every
particle bump had before the table; the ratio is anchor ÷ median episode. Load averages before
and after. Asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.localization import ParticleLocalizationPolicy
from baselines.navigation.continuous import ContinuousNavigationPlanner
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.bump_sampler import default_max_ticks, reset_drives, simulate_bumps

NOISE = {"type": "reliable", "r": 0.9, "eps_deg": 5}
DYNAMIC = {"backend": "pymunk", "physics": "dynamic", "noise": NOISE}
GOAL = {"goal_radius": 0.3, "heading_tolerance_deg": 10, "observe_task": True}
GRID_MAP = str(Path(__file__).parents[1] / "configs" / "maps" / "bench_grid_14x22.yaml")
FIRST_SEED = 10_000
#: the localization env, whose episodes are cut at ``--bumps`` bumps (no claim filter ends them)
LOCALIZATION = "bounce_gym/BounceLocalization-v0"
#: (row, env id, env arguments, planner factory)
ROWS = (
    ("search planner, lab", "bounce_gym/BounceNavigation-v0",
     {**DYNAMIC, "angles": [45, 90, 135], "task_kwargs": GOAL},
     lambda: ContinuousNavigationPlanner(horizon=200)),
    ("search planner, generated grid", "bounce_gym/BounceNavigation-v0",
     {**DYNAMIC, "world": GRID_MAP, "angles": [45, 90, 135], "task_kwargs": GOAL},
     lambda: ContinuousNavigationPlanner(horizon=200)),
    ("continuous-angle planner, lab", "bounce_gym/BounceNavigation-v0",
     {**DYNAMIC, "action_type": "continuous", "task_kwargs": GOAL},
     lambda: ContinuousNavigationPlanner(horizon=200)),
    ("particle localization (10,000 particles), lab", LOCALIZATION,
     {**DYNAMIC, "angles": [45, 135], "task_kwargs": {"filter_factory": None}},
     lambda: ParticleLocalizationPolicy(particles=10_000)),
)


def planner_episode(env, planner, seed: int, bumps: int | None) -> float:
    """Seconds the planner spent in one episode (``bumps``: stop after that many steps)."""
    obs, info = env.reset(seed=seed)
    spent = time.perf_counter()
    planner.start_options(env, seed)
    planner.reset(env)
    spent = time.perf_counter() - spent
    for _ in range(bumps or 10**9):
        start = time.perf_counter()
        action = planner.act(obs, None)
        spent += time.perf_counter() - start
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return spent


def anchor_seconds(particles: int = 10_000, world: str = "lab_localization_a") -> float:
    """One bump of ``particles`` particles through the simulator itself, from contact poses
    the simulator produced (uniform starts driven to their first contact)."""
    env = gym.make("bounce_gym/BounceLocalization-v0", **DYNAMIC, world=world, angles=[45, 135],
                   task_kwargs={"filter_factory": None})
    env.reset(seed=FIRST_SEED)
    base = env.unwrapped
    dynamics, model = base.options.robot_dynamics, base.cell_model()
    rng = np.random.default_rng(0)
    params = dict(dynamics)
    starts = BounceDynamics(params.pop("world"), particles, robot_collisions="ignore",
                            **params).reset(rng)
    max_ticks = default_max_ticks(dynamics)
    state, point, heading, _ = reset_drives(model, dynamics, starts.position, starts.heading,
                                            rng, max_ticks)
    start = time.perf_counter()
    simulate_bumps(model, np.radians([45.0]), np.zeros(particles, dtype=np.int64), point,
                   heading, rng, dynamics, max_ticks)
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10, help="episodes per row and round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--bumps", type=int, default=40,
                        help="localization: bumps per episode")
    parser.add_argument("--rows", nargs="+", metavar="WORD",
                        help="only the rows whose name contains one of these words")
    args = parser.parse_args(argv)
    rounds = max(3, args.rounds)
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    anchor = anchor_seconds()
    print(f"anchor: one bump of 10,000 particles through the simulator: {anchor:.2f} s")
    out = {"anchor_seconds": anchor}
    for row, env_id, kwargs, make in ROWS:
        if args.rows and not any(word in row for word in args.rows):
            continue
        env = gym.make(env_id, **kwargs)
        planner = make()
        planner_episode(env, planner, FIRST_SEED - 1 + 10**6, 1)  # builds or loads the table
        medians, every = [], []
        for r in range(rounds):
            seeds = range(FIRST_SEED + r * args.episodes, FIRST_SEED + (r + 1) * args.episodes)
            times = [planner_episode(env, planner, seed,
                                     args.bumps if env_id == LOCALIZATION else None)
                     for seed in seeds]
            medians.append(float(np.median(times)))
            every += times
        median = float(np.median(every))
        out[row] = {"median": median, "p90": float(np.quantile(every, 0.9)),
                    "max": max(every), "round_medians": medians}
        print(f"{row}: median {median:.2f} s per episode (rounds {min(medians):.2f}–"
              f"{max(medians):.2f}), 90th percentile {out[row]['p90']:.2f} s, max "
              f"{out[row]['max']:.2f} s, n = {len(every)}; anchor ÷ median {anchor / median:.2f}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return out


if __name__ == "__main__":
    main()
