"""The best fixed angle per episode in hindsight: an oracle row that measures what partial
observability costs a fixed-angle robot.

A robot that senses only contact and time cannot know which of its bounce angles suits the
episode it is in; an observer who has seen every fixed-angle policy run from the same seed can.
For each seed this row takes the outcome of the fixed-angle policy that did best on that seed
(the family's ranking, `bounce_gym_experiments.families.base.Family.rank`: its score, then fewer ticks;
ties go to the first angle of Φ). It is computed from the fixed rows, runs no episode of its
own, and no real policy can match it in general; the gap between it and the best single fixed
angle is the value of knowing, per episode, which angle to commit to.
"""

from __future__ import annotations

import dataclasses

#: The oracle row's policy name.
ORACLE_NAME = "oracle: best fixed angle per episode (hindsight)"


def best_fixed_in_hindsight(rows: list, fixed: list[str], family) -> list:
    """One row per seed: a copy of the best of the ``fixed`` policies' rows of that seed (by
    ``family.rank``), named `ORACLE_NAME`, with ``oracle_choice`` the chosen policy. None unless
    there are at least two fixed policies."""
    if len(fixed) < 2:
        return []
    order = {name: i for i, name in enumerate(fixed)}
    by_seed: dict[int, list] = {}
    for r in rows:
        if r.policy in order:
            by_seed.setdefault(r.seed, []).append(r)
    out = []
    for candidates in by_seed.values():
        best = max(sorted(candidates, key=lambda r: order[r.policy]),
                   key=lambda r: family.rank(r.row()))
        out.append(dataclasses.replace(best, policy=ORACLE_NAME, group=None,
                                       metrics={**best.metrics, "oracle_choice": best.policy}))
    return out
