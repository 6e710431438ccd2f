"""Bounce visibility graph timings and the random-polygon reachability experiment of
Nilles et al. 2021, §7.3.

Run with ``python -m benchmarks.visibility`` (``--per-cell``, ``--seed``). Prints tables and the
[BENCH-tolerance] check "every cell's mean unreachable fraction < 0.05" (Figs. 15-16).

* Partition (Alg. 1) and G_safe construction time for ``two_rooms``, ``simple_bit`` and random
  star polygons with 20 / 50 / 100 vertices (irregularity scaled as 0.2 * 20 / n so the
  generator finds simple polygons).
* The grid irregularity ∈ linspace(0.1, 0.4, 5) × spikiness ∈ linspace(0.1, 0.5, 5), 10 polygons
  per cell (20 vertices, centre (250, 250), average radius 100; non-simple draws are rejected
  and redrawn by the generator): per cell the mean unreachable fraction of the perimeter, mean
  numbers of SCCs and WCCs of G_safe, mean |P'| and runtime.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from baselines.visibility.graph import reachability, safe_graph
from baselines.visibility.partition import partition
from baselines.visibility.planning import fewest_bounce_plan
from bounce_gym.worlds import get
from bounce_gym.worlds.generators import random_star_polygon

IRREGULARITY = np.linspace(0.1, 0.4, 5)
SPIKINESS = np.linspace(0.1, 0.5, 5)


def _timed(world):
    t0 = time.perf_counter()
    part = partition(world)
    t1 = time.perf_counter()
    g = safe_graph(part)
    t2 = time.perf_counter()
    # one plan: fewest bounces from segment 0 to the segment halfway round the boundary
    plan = fewest_bounce_plan(g, 0, part.n // 2)
    t3 = time.perf_counter()
    return part, g, t1 - t0, t2 - t1, t3 - t2, plan


def timings(seed: int = 0) -> list[dict]:
    rng = np.random.default_rng(seed)
    cases = [("two_rooms", get("two_rooms")), ("simple_bit", get("simple_bit"))]
    for n in (20, 50, 100):
        cases.append((f"star_{n}", random_star_polygon(rng, n, irregularity=0.2 * 20 / n,
                                                        spikiness=0.3)))
    rows = []
    print(f"{'world':<12} {'|P|':>5} {'|P_prime|':>9} {'arcs':>7} {'partition s':>12} "
          f"{'G_safe s':>10} {'plan s':>9} {'plan arcs':>9}")
    for name, world in cases:
        part, g, tp, tg, tplan, plan = _timed(world)
        arcs = "none" if plan is None else str(plan.n_arcs)
        rows.append(dict(world=name, n=world.n_edges, nodes=part.n, arcs=g.number_of_edges(),
                         partition_s=tp, safe_graph_s=tg, plan_s=tplan))
        print(f"{name:<12} {world.n_edges:>5} {part.n:>9} {g.number_of_edges():>7} "
              f"{tp:>12.4f} {tg:>10.4f} {tplan:>9.5f} {arcs:>9}")
    return rows


def reachability_grid(per_cell: int = 10, seed: int = 0) -> list[dict]:
    rng = np.random.default_rng(seed)
    rows = []
    print(f"\n{'irr':>6} {'spike':>6} {'unreach':>8} {'max':>7} {'SCCs':>6} {'WCCs':>6} "
          f"{'|P_prime|':>9} {'some>0':>7} {'s/poly':>7}")
    for irr in IRREGULARITY:
        for spike in SPIKINESS:
            fr, scc, wcc, size, dt = [], [], [], [], []
            for _ in range(per_cell):
                world = random_star_polygon(rng, 20, irregularity=float(irr),
                                            spikiness=float(spike))
                t0 = time.perf_counter()
                part = partition(world)
                reach = reachability(safe_graph(part), part)
                dt.append(time.perf_counter() - t0)
                fr.append(reach.unreachable_fraction)
                scc.append(reach.n_sccs)
                wcc.append(reach.n_wccs)
                size.append(part.n)
            row = dict(irregularity=float(irr), spikiness=float(spike),
                       unreachable=float(np.mean(fr)), unreachable_max=float(np.max(fr)),
                       sccs=float(np.mean(scc)), wccs=float(np.mean(wcc)),
                       nodes=float(np.mean(size)), some=float(np.mean(np.asarray(fr) > 0)),
                       seconds=float(np.mean(dt)))
            rows.append(row)
            print(f"{irr:>6.3f} {spike:>6.2f} {row['unreachable']:>8.4f} "
                  f"{row['unreachable_max']:>7.4f} {row['sccs']:>6.2f} {row['wccs']:>6.2f} "
                  f"{row['nodes']:>9.1f} {row['some']:>7.2f} {row['seconds']:>7.3f}")
    return rows


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-cell", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rows_t = timings(args.seed)
    rows_g = reachability_grid(args.per_cell, args.seed)
    worst = max(r["unreachable"] for r in rows_g)
    ok = worst < 0.05
    print(f"\n[BENCH-tolerance] every cell's mean unreachable fraction < 0.05: "
          f"{'PASS' if ok else 'FAIL'} (largest cell mean {worst:.4f}; cell means "
          f"{min(r['unreachable'] for r in rows_g):.4f}-{worst:.4f}; SCC means "
          f"{min(r['sccs'] for r in rows_g):.1f}-{max(r['sccs'] for r in rows_g):.1f}; WCC means "
          f"{min(r['wccs'] for r in rows_g):.1f}-{max(r['wccs'] for r in rows_g):.1f})")
    return dict(timings=rows_t, grid=rows_g, passed=ok)


if __name__ == "__main__":
    main()
