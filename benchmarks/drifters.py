"""Drifters (issue #15): the GCM of a 10^6-cell layer and continuous advection against Parcels.

Run with ``python -m benchmarks.drifters`` (``--quick``: a 300 x 300 layer, fewer particles).
Prints rows; asserts nothing.

* **GCM of one layer** (thesis Alg. 5.1 PersistentBehavior on `DrifterCells`, ρ = 0.8): a
  1000 x 1000 all-water layer (10^6 cells) whose flow is the gradient of a seeded Gaussian random
  field (white noise smoothed over 15 cells) with an inward push within ~8 cells of the edges, so
  every drifter ends in one of a few hundred sinks. Timed: the cell model and its sparse drift
  matrix; `generalized_cell_mapping` (persistent groups, stationary distributions, the long-run
  mix, which factorises I - Q once); the absorption times (one solve with that factor); the
  transient groups by domicile set. Target: the analysis (everything after the matrix) <= 10 s.
  The residual max |(I - Q) a - 1| says how well the absorption times are resolved: a chain
  that needs many unlikely moves in a row to leave a region has expected times beyond what
  float64 resolves, and then the residual is large.
* **Advection**: particles x steps per second of `Drifters` (RK4, no diffusion) and of Parcels'
  ``AdvectionRK4`` (float64 particles) on the same time-dependent double gyre, the same particles,
  the same dt and number of steps, measured in the same run; the ratio ours / Parcels.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.ndimage import gaussian_filter

from bounce_gym.cells import DrifterCells
from bounce_gym.dynamics.advection import Drifters
from bounce_gym.flows import FlowField, get_flow
from bounce_gym.markov.gcm import layer_gcm


def random_gradient_layer(n: int, length: float = 15.0, seed: int = 0) -> FlowField:
    """An n x n all-water layer (1 km cells) flowing up the gradient of a smooth random field,
    pushed inwards near the edges."""
    rng = np.random.default_rng(seed)
    phi = gaussian_filter(rng.standard_normal((n, n)), length, mode="wrap")
    j, i = np.mgrid[0:n, 0:n]
    edge = np.minimum(np.minimum(i, n - 1 - i), np.minimum(j, n - 1 - j))
    phi = phi - 5.0 * phi.std() * np.exp(-edge / 8.0)
    gy, gx = np.gradient(phi)
    x = 1000.0 * np.arange(n)
    return FlowField(gx[None], gy[None], x=x, y=x, name=f"random_gradient_{n}")


def _row(name: str, value: str, note: str = "") -> None:
    print(f"{name:<52} {value:>16}  {note}")


def bench_gcm(n: int) -> dict:
    field = random_gradient_layer(n)
    start = time.perf_counter()
    model = DrifterCells(field, rho=0.8)
    P = model.transition_matrix(0)
    build = time.perf_counter() - start
    start = time.perf_counter()
    res = layer_gcm(model, 0)
    groups = time.perf_counter() - start
    start = time.perf_counter()
    a = res.absorption_time
    absorption = time.perf_counter() - start
    start = time.perf_counter()
    transient_groups = res.domicile_groups()
    domiciles = time.perf_counter() - start
    q = P[res.transient][:, res.transient]
    residual = float(np.abs(a - q @ a - 1.0).max()) if len(a) else 0.0
    total = groups + absorption + domiciles
    print(f"GCM of one layer: {n} x {n} = {model.n_states:,} cells, rho = 0.8")
    _row("  DrifterCells + drift matrix [s]", f"{build:.2f}", f"({P.nnz:,} transitions)")
    _row("  groups + stationary + long-run mix [s]", f"{groups:.2f}")
    _row("  absorption times a = (I - Q)^-1 1 [s]", f"{absorption:.2f}")
    _row("  transient groups by domicile set [s]", f"{domiciles:.2f}")
    _row("  analysis total [s]", f"{total:.2f}",
         f"(target <= 10 s: {'ok' if total <= 10 else 'above target'})")
    _row("  persistent groups / transient groups", f"{res.n_groups} / {len(transient_groups)}")
    _row("  transient cells", f"{len(res.transient):,}")
    _row("  absorption time median / max", f"{np.median(a):.1f} / {a.max():.3g}")
    _row("  residual max |(I - Q) a - 1|", f"{residual:.2g}")
    return dict(build=build, analysis=total, residual=residual)


def bench_advection(n_particles: int, n_steps: int, repeats: int) -> dict:
    from bounce_gym.flows.parcels_bridge import parcels_advect, to_parcels_fieldset

    field = get_flow("double_gyre")
    rng = np.random.default_rng(0)
    x, y = rng.uniform(0.05, 1.95, n_particles), rng.uniform(0.05, 0.95, n_particles)
    dt = 0.05
    fieldset = to_parcels_fieldset(field)
    ours = theirs = 0.0
    for _ in range(repeats):
        drifters = Drifters(field, x, y, 0)
        start = time.perf_counter()
        for _ in range(n_steps):
            drifters.step(dt)
        ours = max(ours, n_particles * n_steps / (time.perf_counter() - start))
        start = time.perf_counter()
        px, py = parcels_advect(field, x, y, 0, dt, n_steps, fieldset=fieldset)
        theirs = max(theirs, n_particles * n_steps / (time.perf_counter() - start))
    gap = max(np.abs(px - drifters.x).max(), np.abs(py - drifters.y).max())
    print(f"Advection, double gyre, {n_particles:,} particles x {n_steps} RK4 steps "
          f"(best of {repeats})")
    _row("  Drifters particle-steps/s", f"{ours:,.0f}")
    _row("  Parcels AdvectionRK4 particle-steps/s (anchor)", f"{theirs:,.0f}")
    _row("  ratio Drifters / Parcels", f"{ours / theirs:.1f}")
    _row("  largest position difference", f"{gap:.1g}")
    return dict(ours=ours, parcels=theirs)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 300 x 300 layer, fewer particles")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    bench_gcm(300 if args.quick else 1000)
    print()
    bench_advection(1_000 if args.quick else 10_000, 50 if args.quick else 100, args.repeats)


if __name__ == "__main__":
    main()
