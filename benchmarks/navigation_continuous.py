"""Navigation with continuous bounce angles: the continuous-angle planner on the lab map.
Run with ``python -m benchmarks.navigation_continuous [--episodes N] [--noise]``.

Episodes: BounceNavigation-v0 on the kinematic backend (or ``--backend pymunk --physics ...``,
where the search's budget flags make it affordable) with ``action_type: continuous``
(45°–135°), goal radius 0.3, heading tolerance 10°, 200 steps, the env's own random start and
goal poses from held-out seeds 10,000 + i — as the rows ``navigation-lab-continuous-*`` of
configs/eval_physics.yaml. Per episode, with the navigation family's own checks: whether the
pair is cell-feasible (the roadmap of the env's cell model with Φ = {45°, 90°, 135°} has a plan)
and world-reachable (random continuous-angle walks reach it, `baselines.navigation.reachability`;
kinematic backend and pymunk's dynamic physics only, counted as not reachable elsewhere),
the planner's success and its predicted success, and the planner's own time (its ``reset`` and
``act`` calls, on one core). Prints success on all, cell-feasible and world-reachable pairs with
95 % Wilson intervals and counts, the mean prediction beside it (± its 95 % t-interval), and the
median time per episode. Asserts nothing.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
from scipy import stats

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.navigation.continuous import ContinuousNavigationPlanner
from bounce_gym_experiments.families.navigation import (
    WALK_MODELS,
    Feasibility,
    WorldReachability,
)
from bounce_gym_experiments.stats import wilson_interval

ENV_ID = "bounce_gym/BounceNavigation-v0"
KWARGS = {"backend": "kinematic", "action_type": "continuous", "angles": [45, 90, 135],
          "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}}
FIRST_SEED = 10_000
HORIZON = 200


def _episode(env, planner: ContinuousNavigationPlanner, seed: int) -> tuple[bool, float]:
    """Whether the planner reached the goal, and the seconds its own calls took."""
    obs, _ = env.reset(seed=seed)
    start = time.perf_counter()
    planner.reset(env)
    spent = time.perf_counter() - start
    while True:
        start = time.perf_counter()
        action = planner.act(obs, {})
        spent += time.perf_counter() - start
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return bool(info["is_success"]), spent


def _report(label: str, rows: list[dict], mask: list[bool]) -> None:
    chosen = [r for r, m in zip(rows, mask, strict=True) if m]
    if not chosen:
        print(f"  {label:<16} n = 0")
        return
    wins, n = sum(r["success"] for r in chosen), len(chosen)
    lo, hi = wilson_interval(wins, n)
    pred = np.array([r["predicted"] for r in chosen])
    half = (stats.t.ppf(0.975, n - 1) * pred.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan
    print(f"  {label:<16} success {wins}/{n} = {wins / n:.3f} [{lo:.3f}, {hi:.3f}]; "
          f"predicted {pred.mean():.3f} ± {half:.3f}")


def main(argv: list[str] | None = None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED)
    parser.add_argument("--noise", action="store_true",
                        help="rotation noise: reliable, r = 0.9, eps = 5 degrees")
    parser.add_argument("--backend", default="kinematic")
    parser.add_argument("--physics", default=None)
    parser.add_argument("--grid-deg", type=float, default=2.0)
    parser.add_argument("--frontier", type=int, default=300)
    parser.add_argument("--search-bumps", type=int, default=20)
    parser.add_argument("--search-nodes", type=int, default=6_000)
    parser.add_argument("--episode-searches", type=int, default=8)
    args = parser.parse_args(argv)
    kwargs = {**KWARGS, "backend": args.backend}
    if args.physics:
        kwargs["physics"] = args.physics
    if args.noise:
        kwargs["noise"] = {"type": "reliable", "r": 0.9, "eps_deg": 5}
    env = gym.make(ENV_ID, **kwargs)
    feasible, reachable = Feasibility(), WorldReachability(HORIZON)
    planner = ContinuousNavigationPlanner(
        horizon=HORIZON, grid_deg=args.grid_deg, frontier=args.frontier,
        search_bumps=args.search_bumps, search_nodes=args.search_nodes,
        episode_searches=args.episode_searches)
    rows = []
    for seed in range(args.first_seed, args.first_seed + args.episodes):
        env.reset(seed=seed)
        checks = {"feasible": feasible(env),
                  "reachable": (env.unwrapped.options.backend, env.unwrapped.options.physics)
                  in WALK_MODELS and reachable(env)}
        success, spent = _episode(env, planner, seed)
        rows.append({**checks, "success": success, "predicted": planner.predicted_success,
                     "seconds": spent})
    print(f"{ENV_ID} {kwargs}: {len(rows)} episodes from seed {args.first_seed}, "
          f"{sum(r['feasible'] for r in rows)} cell-feasible, "
          f"{sum(r['reachable'] for r in rows)} world-reachable")
    _report("all", rows, [True] * len(rows))
    _report("cell-feasible", rows, [r["feasible"] for r in rows])
    _report("world-reachable", rows, [r["reachable"] for r in rows])
    missed = sum(r["success"] and not r["reachable"] for r in rows)
    print(f"  reached by the planner but missed by the random walks: {missed}")
    seconds = np.array([r["seconds"] for r in rows])
    print(f"  planner time per episode: median {np.median(seconds):.2f} s, "
          f"90th percentile {np.quantile(seconds, 0.9):.2f} s, max {seconds.max():.2f} s")
    return rows


if __name__ == "__main__":
    main()
