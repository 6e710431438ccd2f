"""Reporting an evaluation: the per-(experiment, policy) summary, the printed tables, the CSV and
JSON files and the plots. Which table a row goes to, its columns and which of them show
mean ± std come from the experiment's family (`experiments.registry`)."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from bounce_gym.files import atomic_write
from experiments.families.base import Family
from experiments.plots.trajectories import plot_trajectories
from experiments.registry import FAMILIES
from experiments.runner import EpisodeResult


def families_of(plots: Mapping) -> dict[str, Family]:
    """Experiment name → family, from `experiments.runner.run`'s plot data."""
    return {name: data["family"] for name, data in plots.items() if "family" in data}


def summarise(rows: list[EpisodeResult], families: Mapping[str, Family] | None = None
              ) -> list[dict]:
    """Per (experiment, policy): the mean and the population standard deviation (``<key>_std``)
    of every numeric column, over the episodes that have it (``ticks_to_goal`` exists only for
    successful episodes, ``steps_to_full`` only for episodes that reached full coverage), then
    the family's extra columns (e.g. ``full``).

    A column whose values are all the same integer (``robots``) stays that integer.
    """
    families = families or {}
    groups: dict[tuple[str, str], list[dict]] = {}
    for r in rows:
        groups.setdefault((r.experiment, r.policy), []).append(r.row())
    out = []
    for (exp, policy), items in groups.items():
        entry = {"experiment": exp, "policy": policy, "episodes": len(items)}
        keys = list(dict.fromkeys(k for item in items for k in item))
        for key in keys:
            if key in ("experiment", "policy", "seed"):
                continue
            values = [i[key] for i in items if key in i and i[key] is not None]
            if values and all(isinstance(v, bool | int | float | np.floating) for v in values):
                numbers = np.array([float(v) for v in values])
                constant_int = all(isinstance(v, int) and not isinstance(v, bool) and v == values[0]
                                   for v in values)
                entry[key] = values[0] if constant_int else float(numbers.mean())
                entry[f"{key}_std"] = float(numbers.std())
        if exp in families:
            families[exp].summarise(entry, items)
        out.append(entry)
    return out


def format_table(summary: list[dict], families: Mapping[str, Family]) -> str:
    """Plain-text tables of the summary, one per family table heading (families sharing a
    heading share a table; the untitled one first)."""
    tables: dict[str, list[Family]] = {}
    for family in FAMILIES:
        tables.setdefault(family.table, []).append(family)
    blocks = []
    for title, members in tables.items():
        rows = [r for r in summary if families.get(r["experiment"]) in members]
        if rows:
            columns = list(dict.fromkeys(c for f in members for c in f.columns))
            spread = frozenset().union(*(f.spread for f in members))
            counts = frozenset().union(*(f.counts for f in members))
            blocks.append((title + "\n" if title else "")
                          + _table(columns, rows, spread, counts))
    return "\n\n".join(blocks)


def _table(columns: list[str], summary: list[dict], spread: frozenset, counts: frozenset) -> str:
    present = [c for c in columns if any(c in row for row in summary)]

    def number(value) -> str:
        if isinstance(value, float):
            return f"{value:.3f}" if abs(value) < 1000 else f"{value:.0f}"
        return str(value)

    def cell(row: dict, column: str) -> str:
        value = row.get(column)
        if value is None:
            return "-"
        if column in counts:
            return f"{value}/{row['episodes']}"
        if column in spread and f"{column}_std" in row:
            digits = 0 if abs(value) >= 100 else 1 if abs(value) >= 10 else 3
            return f"{value:.{digits}f} ± {row[f'{column}_std']:.{digits}f}"
        return number(value)

    rows = [[cell(r, c) for c in present] for r in summary]
    widths = [max(len(c), *(len(r[i]) for r in rows)) for i, c in enumerate(present)]
    lines = ["  ".join(c.ljust(w) for c, w in zip(present, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(lines)


def write_results(folder: Path, rows: list[dict], summary: list[dict], config: dict) -> None:
    """``episodes.csv`` (one row per episode) and ``results.json`` (config, summary, episodes)."""
    keys = sorted({k for r in rows for k in r}, key=lambda k: (k not in ("experiment", "policy",
                                                                         "seed"), k))
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=keys)
    writer.writeheader()
    writer.writerows(rows)
    atomic_write(folder / "episodes.csv", buf.getvalue().encode())
    payload = {"config": config, "summary": summary, "episodes": rows}
    atomic_write(folder / "results.json", json.dumps(payload, indent=2, default=_jsonable).encode())


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_plots(folder: Path, plots: Mapping, summary: list[dict] | None = None) -> list[Path]:
    """Every experiment's trajectories and its family's plots; given the summary, each family's
    plots across experiments (e.g. steps to full coverage against the number of robots)."""
    written = []
    for name, data in plots.items():
        written += plot_trajectories(folder, name, data)
        if "family" in data:
            written += data["family"].plots(folder, name, data)
    if summary is not None:
        for family in dict.fromkeys(families_of(plots).values()):
            written += family.summary_plots(folder, plots, summary)
    return written
