"""A leaderboard of an evaluation (a configuration with ``leaderboard: true``, e.g.
``configs/benchmark.yaml``): per experiment, its policies ordered by the family's score, every
measured cell with its 95% interval and count.

Writes ``leaderboard.md`` (a section per experiment: env, difficulty, episodes per policy,
horizon, then the table; notes such as model folders without models at the end),
``leaderboard.csv`` (one line per experiment and policy, every estimate with ``_lo``, ``_hi`` and
``_n``) and ``leaderboard.png`` (each experiment's score per policy with its interval).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from bounce_gym.files import atomic_write
from experiments.config import world_name
from experiments.plots.figures import pyplot, save_figure
from experiments.report import cell, csv_text, tables


def ordered(rows: list[dict], family) -> list[dict]:
    """Rows best first by the family's score (rows without it last, order kept among equals)."""
    def key(row):
        score = row.get(family.score)
        if score is None:
            return (1, 0.0)
        return (0, -score if family.higher_is_better else score)

    return sorted(rows, key=key)


def markdown(config: Mapping, summary: list[dict], families: Mapping, notes: list[str],
             provenance: Mapping) -> str:
    """The leaderboard as Markdown (see the module)."""
    experiments = {exp["name"]: exp for exp in config["experiments"]}
    git = provenance.get("git", {})
    lines = [f"# {config['name']}: leaderboard", "",
             f"Commit {git.get('commit', 'unknown')}{' (modified)' if git.get('dirty') else ''}. "
             "Each cell: value [95% interval] n=count. Rates (success, feasible, full) carry "
             "Wilson intervals, means bootstrap intervals; n counts the episodes that have the "
             "value (for a trained algorithm's row, the IQM over its training seeds: n counts "
             "seeds). Rows are ordered by each task's score; overlapping intervals do not rank.",
             ""]
    for heading, columns, rows in tables(summary, families):
        for name in dict.fromkeys(r["experiment"] for r in rows):
            exp, family = experiments[name], families[name]
            mine = ordered([r for r in rows if r["experiment"] == name], family)
            shown = [c for c in columns if c != "experiment" and any(c in r for r in mine)]
            lines += [f"## {name} ({exp.get('difficulty', 'no difficulty given')})", "",
                      f"{heading}: `{exp['env']}` on {world_name(exp)}; {len(exp['seeds'])} episodes per "
                      f"policy (seeds {exp['seeds'][0]}–{exp['seeds'][-1]}), horizon "
                      f"{exp['max_steps']} steps; score: {family.score} "
                      f"({'higher' if family.higher_is_better else 'lower'} is better).", "",
                      "| " + " | ".join(shown) + " |",
                      "|" + "|".join("---" for _ in shown) + "|"]
            lines += ["| " + " | ".join(cell(r, c) for c in shown) + " |" for r in mine]
            lines.append("")
    if notes:
        lines += ["## Notes", ""] + [f"- {note}" for note in notes] + [""]
    return "\n".join(lines)


def csv_rows(config: Mapping, summary: list[dict], families: Mapping) -> list[dict]:
    """The leaderboard's lines for ``leaderboard.csv``."""
    experiments = {exp["name"]: exp for exp in config["experiments"]}
    out = []
    for name in dict.fromkeys(r["experiment"] for r in summary):
        if name not in families:
            continue
        family, exp = families[name], experiments[name]
        for row in ordered([r for r in summary if r["experiment"] == name], family):
            out.append({"experiment": name, "difficulty": exp.get("difficulty", ""),
                        "env": exp["env"], "score": family.score, **row})
    return out


def plot(folder: Path, summary: list[dict], families: Mapping) -> Path | None:
    """Each experiment's score per policy with its 95% interval, one panel per experiment."""
    names = [n for n in dict.fromkeys(r["experiment"] for r in summary) if n in families]
    if not names:
        return None
    plt = pyplot()
    fig, axes = plt.subplots(len(names), 1, figsize=(6.0, 1.1 + 0.32 * len(summary)),
                             squeeze=False)
    for ax, name in zip(axes[:, 0], names, strict=True):
        family = families[name]
        rows = [r for r in ordered([r for r in summary if r["experiment"] == name], family)
                if r.get(family.score) is not None][::-1]
        values = np.array([r[family.score] for r in rows], dtype=float)
        bounds = np.array([[r.get(f"{family.score}_lo"), r.get(f"{family.score}_hi")]
                           for r in rows], dtype=float).reshape(-1, 2)
        bounds = np.where(np.isnan(bounds), values[:, None], bounds)
        ax.errorbar(values, np.arange(len(rows)), xerr=[values - bounds[:, 0],
                                                         bounds[:, 1] - values],
                    fmt="o", capsize=3, color="#2a6fdb")
        ax.set_yticks(np.arange(len(rows)), [r["policy"] for r in rows], fontsize=7)
        ax.set_title(f"{name}: {family.score} (95% CI)", fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
    return save_figure(fig, folder / "leaderboard.png")


def write_leaderboard(folder: Path, config: Mapping, summary: list[dict], families: Mapping,
                      notes: list[str], provenance: Mapping) -> list[Path]:
    """Write ``leaderboard.md``, ``leaderboard.csv`` and ``leaderboard.png``; returns them."""
    md, table = folder / "leaderboard.md", folder / "leaderboard.csv"
    atomic_write(md, markdown(config, summary, families, notes, provenance).encode())
    atomic_write(table, csv_text(csv_rows(config, summary, families),
                                 ("experiment", "difficulty", "env", "policy", "episodes",
                                  "seeds", "score")).encode())
    figure = plot(folder, summary, families)
    return [md, table] + ([figure] if figure is not None else [])
