"""Reporting an evaluation: the per-(experiment, policy) summary with its intervals, the printed
tables, the CSV and JSON files and the plots. Which table a row goes to and its columns come from
the experiment's family (`bounce_gym_experiments.registry`).

A row of a table is a list of runs: a planner or baseline is one run, a trained algorithm one
run per training seed (its models' episodes carry the ``group`` they make one row of; each model
also gets a per-seed row). Every measured column of a row is one estimate of
`bounce_gym_experiments.stats.row_estimate` — the IQM of the runs' means with a two-level
bootstrap interval over runs and their episodes, for rates and means alike — stored as
``<col>`` (the value), ``<col>_lo`` and ``<col>_hi`` (its 95% interval; ``None`` when there is
none) and ``<col>_n`` (how many episodes it rests on: ``ticks_to_goal`` exists only for
successful episodes, ``steps_to_full`` only for those that reached full coverage,
``success_feasible`` only for feasible ones). A family's labels (e.g. ``robots``) are shown as
they are. A table cell reads ``value [lo, hi] n=count``; a learner's row with fewer than
`bounce_gym_experiments.stats.MIN_SEEDS` training seeds is marked in its name (`row_name`).
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from bounce_gym.files import atomic_write
from bounce_gym_experiments import stats
from bounce_gym_experiments.families.base import Family
from bounce_gym_experiments.plots.profiles import plot_profiles
from bounce_gym_experiments.plots.trajectories import plot_trajectories
from bounce_gym_experiments.runner import EpisodeResult

_NOT_MEASURED = frozenset({"experiment", "policy", "seed", "group"})


def families_of(plots: Mapping) -> dict[str, Family]:
    """Experiment name → family, from `bounce_gym_experiments.runner.run`'s plot data."""
    return {name: data["family"] for name, data in plots.items() if "family" in data}


def notes_of(plots: Mapping) -> list[str]:
    """The experiments' notes, from the plot data."""
    return [note for data in plots.values() for note in data.get("notes", [])]


def warnings_of(plots: Mapping) -> list[str]:
    """The experiments' warnings (rows asked for that cannot play, e.g. model folders without
    models), from the plot data."""
    return [line for data in plots.values() for line in data.get("warnings", [])]


def _row(result) -> dict:
    return result.row() if isinstance(result, EpisodeResult) else result


def summarise(rows: list, families: Mapping[str, Family] | None = None) -> list[dict]:
    """Per (experiment, policy), each policy one run: ``episodes`` and every measured column as
    an estimate (see the module), in the order the rows came. ``rows``: `EpisodeResult` or
    their ``row()`` dicts."""
    runs: dict[tuple[str, str], list[dict]] = {}
    for r in map(_row, rows):
        runs.setdefault((r["experiment"], r["policy"]), []).append(r)
    families = families or {}
    return [_entry(exp, policy, [items], families.get(exp)) | _group_of(items)
            for (exp, policy), items in runs.items()]


def table_rows(rows: list, families: Mapping[str, Family] | None = None
               ) -> tuple[list[dict], list[dict]]:
    """The rows the tables show and the per-seed rows. A trained algorithm's models (episodes
    with a ``group``) make one row of several runs, one per training seed, in the place of its
    first model; its per-seed rows (one run each, with their ``group``) are the second list."""
    rows = [_row(r) for r in rows]
    families = families or {}
    keyed: dict[tuple[str, str], dict[str, list[dict]]] = {}
    for r in rows:
        name = r.get("group") or r["policy"]
        keyed.setdefault((r["experiment"], name), {}).setdefault(r["policy"], []).append(r)
    table = []
    for (exp, name), runs in keyed.items():
        entry = _entry(exp, name, list(runs.values()), families.get(exp))
        if any(r.get("group") for items in runs.values() for r in items):
            entry = {**entry, "seeds": len(runs)}
            entry = {k: entry[k] for k in ("experiment", "policy", "episodes", "seeds")} | entry
        table.append(entry)
    per_seed = summarise([r for r in rows if r.get("group")], families)
    return table, per_seed


def _group_of(items: list[dict]) -> dict:
    group = items[0].get("group")
    return {} if group is None else {"group": group}


def _entry(experiment: str, policy: str, runs: list[list[dict]], family: Family | None) -> dict:
    """One summary row over ``runs`` (lists of episode rows): every measured column as
    `bounce_gym_experiments.stats.row_estimate` over the runs' episodes that have it."""
    labels = family.labels if family is not None else frozenset()
    skipped = _NOT_MEASURED | (family.descriptors if family is not None else frozenset())
    entry = {"experiment": experiment, "policy": policy,
             "episodes": sum(len(items) for items in runs)}
    keys = list(dict.fromkeys(k for items in runs for item in items for k in item))
    for key in keys:
        if key in skipped:
            continue
        values = [[i[key] for i in items if i.get(key) is not None] for items in runs]
        flat = [v for run in values for v in run]
        if not flat or not all(isinstance(v, bool | int | float | np.number | np.bool_)
                               for v in flat):
            continue
        if key in labels and all(v == flat[0] for v in flat):
            entry[key] = flat[0]
        else:
            stats.row_estimate(values).store(entry, key)
    return entry


def format_number(value) -> str:
    """A plain number as the tables print it."""
    if isinstance(value, float):
        return f"{value:.3f}" if abs(value) < 1000 else f"{value:.0f}"
    return str(value)


def estimate_text(value: float, lo: float | None, hi: float | None, n: int,
                  small: int = 3) -> str:
    """``value [lo, hi] n=count``, with as many decimals as the value's size calls for
    (``small`` below 10)."""
    size = abs(float(value))
    digits = 0 if size >= 100 else 1 if size >= 10 else small
    interval = "-, -" if lo is None or hi is None else f"{lo:.{digits}f}, {hi:.{digits}f}"
    return f"{float(value):.{digits}f} [{interval}] n={n}"


def row_name(row: dict) -> str:
    """A row's policy name, marked when it is a learner's row with fewer than
    `bounce_gym_experiments.stats.MIN_SEEDS` training seeds (such a row gets no verdict)."""
    seeds = row.get("seeds")
    if seeds is not None and seeds < stats.MIN_SEEDS:
        return f"{row['policy']} [{seeds} seeds < {stats.MIN_SEEDS}]"
    return row["policy"]


def cell(row: dict, column: str, small: int = 3) -> str:
    """One table cell: an estimate with its interval and count (``small`` decimals below 10,
    `estimate_text`), a plain value, or ``-``; the ``policy`` column is the `row_name`."""
    if column == "policy":
        return row_name(row)
    value = row.get(column)
    if value is None:
        return "-"
    if f"{column}_n" in row:
        return estimate_text(value, row[f"{column}_lo"], row[f"{column}_hi"], row[f"{column}_n"],
                             small)
    return format_number(value)


def tables(summary: list[dict], families: Mapping[str, Family]) -> list[tuple[str, list[str],
                                                                              list[dict]]]:
    """``(heading, columns, rows)`` per table, in the order the experiments came; families with
    the same heading share a table (columns merged in order), columns no row has are left out."""
    grouped: dict[str, tuple[list[Family], list[dict]]] = {}
    for row in summary:
        family = families.get(row["experiment"])
        if family is None:
            continue
        members, rows = grouped.setdefault(family.heading, ([], []))
        if family not in members:
            members.append(family)
        rows.append(row)
    out = []
    for heading, (members, rows) in grouped.items():
        columns = list(dict.fromkeys(c for f in members for c in f.columns))
        out.append((heading, [c for c in columns if any(c in r for r in rows)], rows))
    return out


def format_table(summary: list[dict], families: Mapping[str, Family]) -> str:
    """Plain-text tables of the summary rows, one per family heading (see `tables`)."""
    blocks = []
    for heading, columns, rows in tables(summary, families):
        cells = [[cell(r, c) for c in columns] for r in rows]
        widths = [max(len(c), *(len(r[i]) for r in cells)) for i, c in enumerate(columns)]
        lines = [heading, "  ".join(c.ljust(w) for c, w in zip(columns, widths, strict=True)),
                 "  ".join("-" * w for w in widths)]
        lines += ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip()
                  for r in cells]
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)


def csv_text(rows: list[dict], first: tuple[str, ...] = ()) -> str:
    """Rows as CSV: the ``first`` columns, then the others in order of appearance."""
    keys = list(dict.fromkeys([*(k for k in first if any(k in r for r in rows)),
                               *(k for r in rows for k in r)]))
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=keys)
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def write_results(folder: Path, rows: list[dict], summary: list[dict], config: dict,
                  per_seed: list[dict] | None = None, notes: list[str] | None = None,
                  provenance: dict | None = None) -> None:
    """``episodes.csv`` (one row per episode), ``summary.csv`` (the table rows, every estimate
    with ``_lo``, ``_hi`` and ``_n``) and ``results.json``: provenance, the validated config,
    the seeds per experiment, the summary, the per-seed rows of trained models, notes and the
    episodes."""
    atomic_write(folder / "episodes.csv",
                 csv_text(rows, ("experiment", "policy", "seed")).encode())
    atomic_write(folder / "summary.csv",
                 csv_text(summary, ("experiment", "policy", "episodes", "seeds")).encode())
    payload = {"provenance": provenance or {}, "config": config,
               "seeds": {exp["name"]: exp["seeds"] for exp in config["experiments"]},
               "summary": summary, "per_seed": per_seed or [], "notes": notes or [],
               "episodes": rows}
    atomic_write(folder / "results.json", json.dumps(payload, indent=2, default=_jsonable).encode())


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_plots(folder: Path, plots: Mapping, summary: list[dict] | None = None,
                per_seed: list[dict] | None = None) -> list[Path]:
    """Every experiment's trajectories and its family's plots; given the summary, each family's
    plots across experiments (e.g. steps to full coverage against the number of robots); given
    per-seed rows of trained models, their performance profiles."""
    written = []
    for name, data in plots.items():
        if "family" in data:
            written += data["family"].trajectory_plots(folder, name, data)
            written += data["family"].plots(folder, name, data)
        else:
            written += plot_trajectories(folder, name, data)
    if summary is not None:
        for family in dict.fromkeys(families_of(plots).values()):
            written += family.summary_plots(folder, plots, summary)
    if per_seed:
        written += plot_profiles(folder, per_seed, families_of(plots))
    return written
