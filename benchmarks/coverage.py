"""Coverage by mixing bouncing policies (issue 5): the Table I setting on ``lab_complex``.

Run with ``python -m benchmarks.coverage`` (``--seeds``, ``--steps``, ``--epoch``). Prints tables;
asserts nothing.

* The time to compute A (Alg. 3: three GCMs at 65 880 cells = 183 positions x 360 bins,
  Φ = {30°, 75°, 315°}, ε = 5°, r = 0.8) and α (Eq. 5, exact support enumeration).
* α next to the paper's Table I (Alam, Bobadilla & Shell, IRC 2017; thesis Table 3.1), over the
  N cells (the paper) and over the 183 positions (docs/choices/navigation_coverage.md, "Coverage over cells or over
  positions"). ``lab_complex`` is a reconstruction
  (the paper's geometry is unpublished), so only qualitative agreement is expected.
* The analytic residuals ‖Aα − b‖² and distances ‖Aα − b‖ (uniform b) of the optimal mixture, of
  every single policy (α = e_i) and of the uniform mixture, in both spaces.
* A simulation in `BounceEnv` (cell backend, which samples the GCM noise exactly; bounce step mode;
  the coverage task's uniform target over the 183 position cells): ``info["distance"]`` after
  ``--steps`` bounces for ``--seeds`` seeds, for every single policy, the α-mixture over positions
  (the right α for this metric), the α-mixture over cells (the paper's α) and the uniform mixture,
  each mixture run by `MixturePolicy` (time schedule, epochs of ``--epoch`` bumps). "pooled" is
  the distance of the visit histogram summed over the seeds (random starts), closer to the
  start-anywhere model ``A α`` than a single run (docs/choices/navigation_coverage.md, "The limiting distribution starts
  anywhere" and "The mixture's coverage is the model A α").
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from baselines.coverage import (
    DEFAULT_EPOCH,
    MixturePolicy,
    optimal_mixture,
    policy_distributions,
    target_vector,
)
from baselines.policy import FixedAnglePolicy
from bounce_gym.cells import CellModel
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.worlds import get

PHI_DEG = (30.0, 75.0, 315.0)
EPS_DEG, RELIABILITY = 5.0, 0.8
PAPER_ALPHA = (0.22138172, 0.28005791, 0.49856037)


def _row(name: str, value: str, note: str = "") -> None:
    print(f"{name:<44} {value:>24}  {note}")


def analytic() -> dict:
    start = time.perf_counter()
    model = CellModel(get("lab_complex"), n_bins=360)
    model_time = time.perf_counter() - start
    start = time.perf_counter()
    A = policy_distributions(model, np.radians(PHI_DEG), math.radians(EPS_DEG), RELIABILITY)
    a_time = time.perf_counter() - start
    results = {}
    alpha_time = {}
    for space in ("cells", "positions"):
        a_s = A if space == "cells" else A.reshape(model.n_bins, model.n_positions, 3).sum(axis=0)
        b = target_vector(model, None, space)
        start = time.perf_counter()
        results[space] = optimal_mixture(a_s, b)
        alpha_time[space] = time.perf_counter() - start
    print(f"Coverage, lab_complex ({model.n_positions} positions x {model.n_bins} bins = "
          f"{model.n_cells:,} cells), Φ = {{30°, 75°, 315°}}, ε = {EPS_DEG:g}°, r = {RELIABILITY}")
    _row("  CellModel [s]", f"{model_time:.3f}")
    _row("  A: 3 GCMs (groups, stationary, limiting) [s]", f"{a_time:.3f}")
    for space in results:
        _row(f"  α over {space} (support enumeration) [s]", f"{alpha_time[space]:.4f}")
    print("\nα vs Table I (uniform target b)")
    print(f"  {'φ':>6} {'paper':>12} {'ours: cells':>12} {'ours: positions':>16}")
    for i, phi in enumerate(PHI_DEG):
        print(f"  {phi:>5g}° {PAPER_ALPHA[i]:>12.8f} {results['cells'].alpha[i]:>12.8f} "
              f"{results['positions'].alpha[i]:>16.8f}")
    print("\nAnalytic residuals ‖Aα − b‖² (distance ‖Aα − b‖), uniform b")
    print(f"  {'policy':<22} {'cells (n = 65 880)':>24} {'positions (n = 183)':>24}")
    uniform = np.full(3, 1 / 3)
    rows = [(f"{phi:g}° alone", lambda res, i=i: res.vertex_residuals[i])
            for i, phi in enumerate(PHI_DEG)]
    rows.append(("uniform mixture", lambda res: res.residual_of(uniform)))
    rows.append(("α-mixture (own space)", lambda res: res.residual))
    rows.append(("paper's α", lambda res: res.residual_of(np.array(PAPER_ALPHA))))
    for name, f in rows:
        cells, pos = f(results["cells"]), f(results["positions"])
        print(f"  {name:<22} {cells:>14.4e} ({math.sqrt(cells):.5f}) "
              f"{pos:>14.4e} ({math.sqrt(pos):.5f})")
    cross = results["positions"].residual_of(results["cells"].alpha)
    print(f"  {'cells α over positions':<22} {'':>24} {cross:>14.4e} ({math.sqrt(cross):.5f})")
    return {"model": model, **results}


def simulate(results: dict, seeds: int, steps: int, epoch: int) -> None:
    env = BounceEnv(world="lab_complex", task="coverage", backend="cell", cell_bins=360,
                    angles=list(PHI_DEG), noise={"type": "reliable", "r": RELIABILITY,
                                                 "eps_deg": EPS_DEG}, step_mode="bounce")
    target = env.unwrapped.task.target
    pos, cells = results["positions"], results["cells"]
    policies = {f"{phi:g}° alone": (FixedAnglePolicy(i, phi), pos.vertex_residuals[i])
                for i, phi in enumerate(PHI_DEG)}
    policies["uniform mixture"] = (MixturePolicy(np.full(3, 1 / 3), epoch=epoch),
                                   pos.residual_of(np.full(3, 1 / 3)))
    policies["α-mixture (positions)"] = (MixturePolicy(pos.alpha, epoch=epoch), pos.residual)
    policies["α-mixture (cells)"] = (MixturePolicy(cells.alpha, epoch=epoch),
                                     pos.residual_of(cells.alpha))
    print(f"\nSimulated coverage distance (BounceEnv cell backend, L2 to uniform over "
          f"{int(env.unwrapped.task.free.sum())} positions), {seeds} seeds x {steps} bounces, "
          f"epochs of {epoch} bumps")
    print(f"  {'policy':<22} {'‖Aα−b‖':>8} {'mean ± sd':>17} {'min':>7} {'max':>7} "
          f"{'pooled':>7} {'ticks':>7} {'time [s]':>8}  time fractions")
    for name, (policy, residual) in policies.items():
        start = time.perf_counter()
        dist, ticks = [], []
        pooled = np.zeros(target.shape)
        fractions = np.zeros(3)
        for seed in range(seeds):
            obs, info = env.reset(seed=seed)
            policy.reset(env)
            for _ in range(steps):
                obs, _, _, _, info = env.step(policy.act(obs, info))
            dist.append(info["distance"])
            ticks.append(info["ticks"])
            pooled += env.unwrapped.task.visits
            if isinstance(policy, MixturePolicy):
                fractions += policy.time_fractions / seeds
        pooled_d = float(np.linalg.norm(pooled / pooled.sum() - target))
        frac = np.array2string(fractions, precision=3) if fractions.any() else ""
        print(f"  {name:<22} {math.sqrt(residual):>8.4f} {np.mean(dist):>8.4f} ± "
              f"{np.std(dist):.4f} {np.min(dist):>7.4f} {np.max(dist):>7.4f} {pooled_d:>7.4f} "
              f"{np.mean(ticks):>7.0f} {time.perf_counter() - start:>8.1f}  {frac}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=3000, help="bounces per episode")
    parser.add_argument("--epoch", type=int, default=DEFAULT_EPOCH, help="bumps per epoch")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    results = analytic()
    if args.seeds > 0 and args.steps > 0:
        simulate(results, args.seeds, args.steps, args.epoch)
    print(f"\ntotal {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
