"""Trained agents aggregated over their training seeds.

Every model file (``<algo>_seed<N>.zip``) is one run of its algorithm; its episodes are
summarised on their own first (one per-seed row, `bounce_gym_experiments.report.summarise`). Following
Agarwal et al. (NeurIPS 2021), the table then shows one row per algorithm: for every measured
column the interquartile mean (IQM) of the per-seed means, with a stratified-bootstrap 95%
interval over the seeds (`bounce_gym_experiments.stats.iqm_estimate`); the column's count is the number of
seeds that have the column, ``seeds`` the number of training seeds and ``episodes`` all their
episodes. Episodes and per-seed rows are kept in the results files.
"""

from __future__ import annotations

from bounce_gym_experiments import stats


def aggregate_training_seeds(summary: list[dict], groups: dict[tuple[str, str], str]
                             ) -> tuple[list[dict], list[dict]]:
    """The table rows and the per-seed rows.

    ``summary``: per (experiment, policy) rows; ``groups``: (experiment, policy) → the group
    it is aggregated into (policies not listed keep their own row). A group's row takes the
    place of its first member; per-seed rows get a ``group`` key.
    """
    members: dict[tuple[str, str], list[dict]] = {}
    for entry in summary:
        group = groups.get((entry["experiment"], entry["policy"]))
        if group is not None:
            members.setdefault((entry["experiment"], group), []).append(entry)
    table, per_seed, done = [], [], set()
    for entry in summary:
        group = groups.get((entry["experiment"], entry["policy"]))
        if group is None:
            table.append(entry)
            continue
        per_seed.append({**entry, "group": group})
        if (entry["experiment"], group) not in done:
            done.add((entry["experiment"], group))
            table.append(aggregate(entry["experiment"], group,
                                   members[(entry["experiment"], group)]))
    return table, per_seed


def aggregate(experiment: str, group: str, seeds: list[dict]) -> dict:
    """One row over the per-seed rows ``seeds`` of a group (see the module)."""
    out = {"experiment": experiment, "policy": group,
           "episodes": sum(s["episodes"] for s in seeds), "seeds": len(seeds)}
    keys = list(dict.fromkeys(k for s in seeds for k in s))
    for key in keys:
        if f"{key}_n" in keys:
            values = [s[key] for s in seeds if s.get(key) is not None]
            stats.iqm_estimate(values).store(out, key)
        elif key not in out and not key.endswith(("_lo", "_hi", "_n")):
            values = [s.get(key) for s in seeds]
            if all(v == values[0] for v in values):  # a label, e.g. the number of robots
                out[key] = values[0]
    return out

