"""Speed of the combinatorial localization filters (issue 4): NFA → DFA conversion and updates.

Run with ``python -m benchmarks.localization``. Prints a table; asserts nothing (the target, not a
test: ≤ 50 ms per 152-cell lab map, where the paper's JFLAP conversion took 20–71 s, Table I).
Each time is the best of ``--repeats`` runs on one process (one core).

Rows:

* ``build_dfa``: lazy subset construction plus knowledge cycles and colours, from the SCM arrays.
* ``SCM + build_dfa``: the same including the cell model's successor arrays for φ.
* ``policy DFA``: the closed-loop automaton of the depth-1 angle-switching planner with
  Φ = {45°, 135°} (beyond the paper), with a fresh planner each run.
* ``filter update``: one `LocalizationFilter.update` (a table lookup), averaged over 100 000.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

from baselines.localization import AngleSwitchPlanner, build_policy_dfa
from bounce_gym import worlds
from bounce_gym.cells import CellModel
from bounce_gym.markov.automata import build_dfa
from bounce_gym.markov.filters import LocalizationFilter

PAPER_TABLE_1 = {  # (map, φ°) -> (DFA states, JFLAP conversion time in s)
    ("lab_localization_a", 45): (129, 24.0),
    ("lab_localization_a", 135): (124, 20.0),
    ("lab_localization_b", 45): (147, 27.0),
    ("lab_localization_b", 135): (202, 71.0),
}

ANGLES = (math.radians(45), math.radians(135))  # Φ of the policy-DFA row


def best_time(run: Callable[[], object], repeats: int) -> float:
    """Best wall-clock time (s) of ``repeats`` calls."""
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def update_time(filt: LocalizationFilter, symbols: list[int]) -> float:
    """Mean time (s) of one filter update over a long observation stream."""
    start = time.perf_counter()
    for a in symbols:
        filt.update(a)
    return (time.perf_counter() - start) / len(symbols)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args(argv)
    print(f"{'map':<20} {'phi':>4} {'N':>5} {'DFA':>5} {'paper':>5} {'build_dfa ms':>13} "
          f"{'SCM+DFA ms':>11} {'policy ms':>10} {'update us':>10} {'paper s':>8}")
    for (name, degrees), (paper_states, paper_s) in PAPER_TABLE_1.items():
        model = CellModel(worlds.get(name), n_bins=8)
        phi = math.radians(degrees)
        succ, bump = model.successor(phi)
        dfa = build_dfa(succ, bump)
        t_dfa = best_time(lambda s=succ, b=bump: build_dfa(s, b), args.repeats)
        t_all = best_time(lambda m=model, p=phi: build_dfa(*m.successor(p)), args.repeats)
        t_policy = best_time(
            lambda m=model: build_policy_dfa(AngleSwitchPlanner(m, ANGLES)), args.repeats)
        # a true stream: the SCM rollout from a fixed start cell, 100 000 ticks
        z, symbols = 0, []
        for _ in range(100_000):
            symbols.append(int(bump[z]))
            z = int(succ[z])
        t_update = update_time(LocalizationFilter(dfa), symbols)
        print(f"{name:<20} {degrees:>4} {model.n_cells:>5} {dfa.n_states:>5} {paper_states:>5} "
              f"{t_dfa * 1e3:>13.2f} {t_all * 1e3:>11.2f} {t_policy * 1e3:>10.2f} "
              f"{t_update * 1e6:>10.3f} {paper_s:>8.0f}", flush=True)
    print(f"\n(best of {args.repeats}; DFA sizes without the trap state, docs/choices/localization.md; "
          f"the lab maps are reconstructions, docs/choices/cell_model.md)")


if __name__ == "__main__":
    main()
