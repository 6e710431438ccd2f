"""Navigation in the continuous world: the sampled-GCM planner against the open-loop roadmap
(issue 24). Run with ``python -m benchmarks.navigation_sampled [--episodes N] [--backend B]``.

Episodes as in the issue's table: BounceNavigation-v0 (lab_navigation, Φ = {45°, 90°, 135°},
goal radius 0.3, heading tolerance 10°, 200 steps), start and goal drawn as on the cell backend
(cell centres and bin headings) from held-out seeds 10,000 + i, then run in the chosen backend.
Feasible = the exact cell model's roadmap has a plan. Prints success on the feasible episodes
with 95 % Wilson intervals, the sampled planner's mean predicted success (mean ± 95 % t-interval)
and the model's build time (docs/sampled_models.md); without noise also the upper bound of any
planner: the episodes whose goal some sequence of angles reaches at all, found by expanding
every bump pose reachable from the first bump (`baselines.navigation.search`). Asserts nothing.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
from scipy import stats

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.navigation import NavigationPlanner
from baselines.navigation.roadmap import goal_cells
from baselines.navigation.sampled import SampledNavigationPlanner
from baselines.navigation.search import shortest_plan
from bounce_gym_experiments.stats import wilson_interval

ENV_ID = "bounce_gym/BounceNavigation-v0"
KWARGS = {"angles": [45, 90, 135], "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}}
FIRST_SEED = 10_000


def _episode(env, policy, seed: int, options: dict) -> bool:
    obs, info = env.reset(seed=seed, options=options)
    policy.reset(env)
    while True:
        obs, _, terminated, truncated, info = env.step(policy.act(obs, info))
        if terminated or truncated:
            return bool(info["is_success"])


def _reachable(env, planner: SampledNavigationPlanner, seed: int, options: dict) -> bool | None:
    """Whether any sequence of angles takes the robot from its first bump to the goal within
    the horizon (None: the search hit its node limit before deciding)."""
    obs, _ = env.reset(seed=seed, options=options)
    planner.reset(env)
    planner.act(obs, {})  # conditions the belief on the first clock: one exact pose
    found = shortest_plan(planner.simulate, planner.point[0], float(planner.heading[0]),
                          planner.plan.n_actions, None, planner.steps_total, 10**6, 1.0, 1.0)
    return True if found.found else (False if found.exhausted else None)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--backend", default="kinematic")
    parser.add_argument("--physics", default=None)
    parser.add_argument("--samples", type=int, default=50)
    parser.add_argument("--depth", type=int, default=3)
    parser.add_argument("--reach", type=int, default=30)
    parser.add_argument("--cell-size", type=float, default=0.25)
    parser.add_argument("--particles", type=int, default=32)
    parser.add_argument("--draws", type=int, default=512)
    parser.add_argument("--no-rollouts", action="store_true",
                        help="value the look-ahead's leaves by the model (QMDP with --depth 1)")
    parser.add_argument("--noise", action="store_true",
                        help="rotation noise: reliable, r = 0.9, eps = 5 degrees")
    args = parser.parse_args(argv)
    extra = {"physics": args.physics} if args.physics else {}
    if args.noise:
        extra["noise"] = {"type": "reliable", "r": 0.9, "eps_deg": 5}
    cell = gym.make(ENV_ID, backend="cell", **KWARGS)
    env = gym.make(ENV_ID, backend=args.backend, **extra, **KWARGS)
    roadmap_planner, planner = NavigationPlanner(), SampledNavigationPlanner(
        samples=args.samples, depth=args.depth, reach=args.reach, cell_size=args.cell_size,
        particles=args.particles, draws=args.draws, rollouts=not args.no_rollouts)
    t0 = time.perf_counter()
    env.reset(seed=0)
    env.unwrapped.cell_model(kind="sampled", samples=args.samples, seed=0, cache=False,
                             heading_offset=None if args.noise else 0.0,
                             cell_size=args.cell_size)
    build = time.perf_counter() - t0
    rows = []
    for i in range(args.episodes):
        seed = FIRST_SEED + i
        cell.reset(seed=seed)
        task = cell.unwrapped.task
        options = {k: {"position": pose[0][0].tolist(), "heading": float(pose[1][0])}
                   for k, pose in (("start", task.start), ("goal", task.goal))}
        roadmap_planner.reset(cell)
        model = cell.unwrapped.cell_model()
        goals = goal_cells(model, task.goal[0][0], float(task.goal[1][0]), task.goal_radius,
                           task.heading_tolerance)
        feasible = roadmap_planner.plan is not None and len(goals) > 0
        old = _episode(env, roadmap_planner, seed, options)
        new = _episode(env, planner, seed, options)
        rows.append((feasible, old, new, planner.predicted_success,
                     None if args.noise else _reachable(env, planner, seed, options)))
    feasible = np.array([r[0] for r in rows])
    print(f"{ENV_ID} backend={args.backend} {extra} {len(rows)} episodes, "
          f"{int(feasible.sum())} feasible; samples/state/angle = {args.samples}; "
          f"model build (cold, one core) {build:.2f} s")
    for name, col in (("roadmap (open loop)", 1), ("sampled SSP + filter", 2)):
        for label, mask in (("feasible", feasible), ("all", np.ones(len(rows), bool))):
            wins = int(sum(r[col] for r, m in zip(rows, mask, strict=True) if m))
            n = int(mask.sum())
            if n == 0:
                print(f"  {name:<22} success on {label:<8} —  n = 0")
                continue
            lo, hi = wilson_interval(wins, n)
            print(f"  {name:<22} success on {label:<8} {wins / max(n, 1):.3f} [{lo:.3f}, {hi:.3f}]"
                  f"  n = {n}")
    if not args.noise:
        for label, mask in (("feasible", feasible), ("all", np.ones(len(rows), bool))):
            known = [r[4] for r, m in zip(rows, mask, strict=True) if m]
            print(f"  upper bound (goal reachable at all) on {label:<8} "
                  f"{sum(k is True for k in known)} of {len(known)}"
                  f" ({sum(k is None for k in known)} undecided)")
    pred = np.array([r[3] for r in rows], dtype=np.float64)
    for label, mask in (("feasible", feasible), ("all", np.ones(len(rows), bool))):
        p = pred[mask]
        if len(p) == 0:
            continue
        half = (stats.t.ppf(0.975, len(p) - 1) * p.std(ddof=1) / np.sqrt(len(p))
                if len(p) > 1 else float("nan"))
        print(f"  predicted success on {label:<8} mean {p.mean():.3f} ± {half:.3f}  n = {len(p)}")
    return {"feasible": feasible, "roadmap": np.array([r[1] for r in rows]),
            "sampled": np.array([r[2] for r in rows]), "predicted": pred, "build_s": build}


if __name__ == "__main__":
    main()
