"""A leaderboard of an evaluation (a configuration with ``leaderboard: true``, e.g.
``configs/benchmark.yaml``): per experiment, its policies ordered by the family's score, every
measured cell with its 95% interval and count.

Writes ``leaderboard.md`` (first "Who wins": per experiment, the best planner against the best
trained agent and against random bouncing, decided by their intervals (`verdicts`); then a
section per experiment: env, difficulty, episodes per policy, horizon, then the table; notes such
as model folders without models at the end),
``leaderboard.csv`` (one line per experiment and policy, every estimate with ``_lo``, ``_hi`` and
``_n``) and ``leaderboard.png`` (each experiment's score per policy with its interval).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from baselines.drifters.policy import AlwaysDriftPolicy, RandomLayerPolicy
from baselines.policy import RandomAnglePolicy
from baselines.rl.policies import GREEDY_SUFFIX
from bounce_gym.files import atomic_write
from bounce_gym_experiments.oracle import ORACLE_NAME
from bounce_gym_experiments.plots.figures import pyplot, save_figure
from bounce_gym_experiments.registry import world_name
from bounce_gym_experiments.report import cell, csv_text, tables


def ordered(rows: list[dict], family) -> list[dict]:
    """Rows best first by the family's score (rows without it last, order kept among equals)."""
    def key(row):
        score = row.get(family.score)
        if score is None:
            return (1, 0.0)
        return (0, -score if family.higher_is_better else score)

    return sorted(rows, key=key)


def kind(policy: str) -> str:
    """``rl``, ``greedy`` (a trained agent's greedy twin), ``random`` (a random angle, or the
    drifter's random layer), ``fixed`` (a fixed angle, or the drifter that never changes
    layer), ``oracle`` or ``planner`` (every other row: the family's reference planners)."""
    if policy.startswith("rl "):
        return "greedy" if policy.endswith(GREEDY_SUFFIX) else "rl"
    if policy in (RandomAnglePolicy.name, RandomLayerPolicy.name):
        return "random"
    if policy.startswith("fixed ") or policy == AlwaysDriftPolicy.name:
        return "fixed"
    return "oracle" if policy == ORACLE_NAME else "planner"


def _best(rows: list[dict], family, which: str) -> dict | None:
    mine = [r for r in ordered(rows, family) if kind(r["policy"]) == which
            and r.get(family.score) is not None]
    return mine[0] if mine else None


def _versus(a: dict | None, b: dict | None, family) -> str:
    """Which of two rows wins on the family's score: the one whose 95% interval lies wholly on
    the better side of the other's; ``tie`` when the intervals overlap."""
    if a is None or b is None:
        return "-"
    score = family.score
    lo_a, hi_a = a.get(f"{score}_lo", a[score]), a.get(f"{score}_hi", a[score])
    lo_b, hi_b = b.get(f"{score}_lo", b[score]), b.get(f"{score}_hi", b[score])
    if None in (lo_a, hi_a, lo_b, hi_b):
        return "undecided (no interval)"
    better_a = lo_a > hi_b if family.higher_is_better else hi_a < lo_b
    better_b = lo_b > hi_a if family.higher_is_better else hi_b < lo_a
    return a["policy"] if better_a else b["policy"] if better_b else "tie (intervals overlap)"


def verdicts(summary: list[dict], families: Mapping) -> list[dict]:
    """Per experiment: its best planner, best trained agent (sampled actions), random's row,
    and who wins between them on the family's score (`_versus`)."""
    out = []
    for name in dict.fromkeys(r["experiment"] for r in summary):
        if name not in families:
            continue
        family = families[name]
        rows = [r for r in summary if r["experiment"] == name]
        planner, rl = _best(rows, family, "planner"), _best(rows, family, "rl")
        random = _best(rows, family, "random")
        out.append({"experiment": name, "score": family.score, "planner": planner, "rl": rl,
                    "random": random, "rl_vs_planner": _versus(rl, planner, family),
                    "rl_vs_random": _versus(rl, random, family)})
    return out


def _verdict_lines(summary: list[dict], families: Mapping) -> list[str]:
    def shown(row, score):
        return "-" if row is None else f"{row['policy']}: {cell(row, score)}"

    lines = ["## Who wins", "",
             "Per experiment, the best planner, the best trained agent (sampled actions; the "
             "greedy rows are in the tables) and random bouncing on the task's score; a policy "
             "wins when its 95% interval lies wholly on the better side of the other's.", "",
             "| experiment | score | best planner | best trained agent | random | RL vs planner "
             "| RL vs random |", "|---|---|---|---|---|---|---|"]
    for v in verdicts(summary, families):
        score = v["score"]
        lines.append(f"| {v['experiment']} | {score} | {shown(v['planner'], score)} | "
                     f"{shown(v['rl'], score)} | {shown(v['random'], score)} | "
                     f"{v['rl_vs_planner']} | {v['rl_vs_random']} |")
    return lines + [""]


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
             "", *_verdict_lines(summary, families)]
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
