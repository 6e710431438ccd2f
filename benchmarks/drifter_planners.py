"""Drifter planners (issue #15, thesis ch. 5): value iteration on 3 x 10^5 states and the
deployment counts of Algs. 5.2 and 5.3.

Run with ``python -m benchmarks.drifter_planners`` (``--quick``: 3 x 100 x 100 states). Prints
rows; asserts nothing.

* **Value iteration** (Alg. 5.5, thesis form, γ = 0.95, until max |ΔV| < 1e-9) on three layers of
  317 x 317 all-water cells (301 467 states) of a seeded smooth random flow (the gradient of a
  Gaussian random field plus half its rotated gradient, turned by -60° and weakened per layer),
  goal in the middle layer. Timed: the solve (the cell model and its matrices are built before).
  Target: <= 10 s.
* **Deployment counts** on ``two_sink`` (ρ = 0.8) and ``scb_like`` at t = 1 h: persistent and
  transient groups (Alg. 5.1), |𝒞| of Alg. 5.2, and |𝒟| and |𝒞| of Alg. 5.3 with d = 6 cells
  (the thesis' range), corners rule.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.ndimage import gaussian_filter

from baselines.drifters import (
    deployment_locations,
    persistent_behavior,
    value_iteration,
    visibility_deployment,
)
from bounce_gym.cells import DrifterCells
from bounce_gym.flows import FlowField, get_flow
from bounce_gym.flows.zoo import ekman_layers


def random_layers(n: int, seed: int = 0) -> FlowField:
    """Three n x n all-water layers (1 km cells) of a smooth seeded random flow."""
    rng = np.random.default_rng(seed)
    phi = gaussian_filter(rng.standard_normal((n, n)), 15.0, mode="wrap")
    gy, gx = np.gradient(phi)
    u, v = ekman_layers(gx - 0.5 * gy, gy + 0.5 * gx, [0.0, 5.0, 10.0], turn_deg=-60.0,
                        e_folding=50.0)
    x = 1000.0 * np.arange(n)
    return FlowField(u, v, x=x, y=x, depth=[0.0, 5.0, 10.0], name=f"random_layers_{n}")


def _row(name: str, value: str, note: str = "") -> None:
    print(f"{name:<52} {value:>16}  {note}")


def bench_value_iteration(n: int, repeats: int) -> float:
    model = DrifterCells(random_layers(n))
    model.action_matrices()
    goal = int(model.state_of(1, n // 2, n // 2))
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        res = value_iteration(model, goal)
        best = min(best, time.perf_counter() - start)
    used = np.bincount(res.policy, minlength=3)
    print(f"Value iteration (Alg. 5.5): 3 x {n} x {n} = {model.n_states:,} states, "
          f"gamma = 0.95, tol 1e-9 (best of {repeats})")
    _row("  solve [s]", f"{best:.2f}", f"(target <= 10 s: {'ok' if best <= 10 else 'above'})")
    _row("  iterations / final max |dV|", f"{res.iterations} / {res.residual:.1g}")
    _row("  policy: drift / up / down", f"{used[0]:,} / {used[1]:,} / {used[2]:,}")
    return best


def deployment_counts() -> None:
    print("Deployment (Algs. 5.1-5.3), surface layer, d = 6 cells, corners rule")
    for name, model in (("two_sink", DrifterCells(get_flow("two_sink"))),
                        ("scb_like 1 h", DrifterCells(get_flow("scb_like"), t=3600.0))):
        start = time.perf_counter()
        b = persistent_behavior(model)
        dep = deployment_locations(b)
        vis = visibility_deployment(model, b, 6)
        took = time.perf_counter() - start
        _row(f"  {name}: persistent / transient groups",
             f"{len(b.groups)} / {len(b.transient_groups)}",
             f"sizes {[len(g) for g in b.groups]} / "
             f"{[len(t) for t in b.transient_groups.values()]}")
        _row(f"  {name}: Alg. 5.2 |C|", f"{len(dep)}")
        _row(f"  {name}: Alg. 5.3 |D| / |C|", f"{len(vis.cover)} / {len(vis)}",
             f"({took:.2f} s for Algs. 5.1-5.3)")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 x 100 x 100 states")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    bench_value_iteration(100 if args.quick else 317, args.repeats)
    print()
    deployment_counts()


if __name__ == "__main__":
    main()
