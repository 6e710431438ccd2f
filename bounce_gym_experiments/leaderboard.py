"""A leaderboard of an evaluation (a configuration with ``leaderboard: true``, e.g.
``configs/benchmark.yaml``): per experiment, its policies ordered by the family's score, every
measured cell with its 95% interval and count.

Writes ``leaderboard.md`` (first "Who wins": per experiment, the best planner, the best trained
agent and random bouncing compared by probability of improvement (`verdicts`); then a
section per experiment: env, difficulty, episodes per policy, horizon, then the table; notes such
as model folders without models at the end),
``leaderboard.csv`` (one line per experiment and policy, every estimate with ``_lo``, ``_hi`` and
``_n``), ``verdicts.csv`` (the "Who wins" rows as text, what README.md's and the docs' result
tables are generated from) and ``leaderboard.png`` (each experiment's score per policy with its
interval).

`who_wins_text` is the same verdicts as plain text in 100 columns, with the winner of each
experiment (`winners`): what ``bounce-gym evaluate`` prints at the end of every evaluation.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from baselines.drifters.fleet import RANDOM_DEPLOYMENT
from baselines.drifters.policy import AlwaysDriftPolicy, RandomLayerPolicy
from baselines.policy import RandomAnglePolicy
from baselines.rl.policies import GREEDY_SUFFIX
from bounce_gym.files import atomic_write
from bounce_gym_experiments import stats
from bounce_gym_experiments.oracle import ORACLE_NAME
from bounce_gym_experiments.plots.figures import pyplot, save_figure
from bounce_gym_experiments.registry import world_name
from bounce_gym_experiments.report import cell, csv_text, row_name, tables


def ordered(rows: list[dict], family) -> list[dict]:
    """Rows best first by the family's score (rows without it last, order kept among equals)."""
    def key(row):
        score = row.get(family.score)
        if score is None:
            return (1, 0.0)
        return (0, -score if family.higher_is_better else score)

    return sorted(rows, key=key)


def kind(policy: str) -> str:
    """``rl``, ``greedy`` (a trained agent's greedy twin), ``random`` (a random angle, the
    drifter's random layer, the fleet's random deployment), ``fixed`` (a fixed angle, or the drifter that never changes
    layer), ``oracle`` or ``planner`` (every other row: the family's reference planners)."""
    if policy.startswith("rl "):
        return "greedy" if policy.endswith(GREEDY_SUFFIX) else "rl"
    if policy in (RandomAnglePolicy.name, RandomLayerPolicy.name, RANDOM_DEPLOYMENT):
        return "random"
    if policy.startswith("fixed ") or policy == AlwaysDriftPolicy.name:
        return "fixed"
    return "oracle" if policy == ORACLE_NAME else "planner"


def _best(rows: list[dict], family, which: str) -> dict | None:
    """The best row of a kind by point value; for trained agents, the best of those with enough
    training seeds for a verdict (else the best of the others, which gets none)."""
    mine = [r for r in ordered(rows, family) if kind(r["policy"]) == which
            and r.get(family.score) is not None]
    enough = [r for r in mine if r.get("seeds", stats.MIN_SEEDS) >= stats.MIN_SEEDS]
    return (enough or mine or [None])[0]


def runs_of(episodes: list[dict], experiment: str, row: dict, score: str) -> list[list[float]]:
    """The score's per-episode values of a table row, one list per run: a trained algorithm's
    row (its episodes carry its ``group``) has one run per model, any other row one."""
    runs: dict[str, list[float]] = {}
    for e in episodes:
        if e["experiment"] != experiment or e.get(score) is None:
            continue
        if e.get("group") == row["policy"] or (e.get("group") is None
                                                and e["policy"] == row["policy"]):
            runs.setdefault(e["policy"], []).append(float(e[score]))
    return list(runs.values())


def _compare(a: dict | None, b: dict | None, episodes: list[dict], experiment: str, family
             ) -> dict | None:
    """P(a improves on b) on the family's score (`bounce_gym_experiments.stats.improvement`) and
    who wins; ``None`` when a row is missing or is a learner's with too few seeds."""
    if a is None or b is None or any(r.get("seeds", stats.MIN_SEEDS) < stats.MIN_SEEDS
                                     for r in (a, b)):
        return None
    p = stats.improvement(runs_of(episodes, experiment, a, family.score),
                          runs_of(episodes, experiment, b, family.score),
                          family.higher_is_better)
    winner = {1: a["policy"], -1: b["policy"], 0: None}[stats.verdict(p)]
    return {"p": p.value, "p_lo": p.lo, "p_hi": p.hi, "winner": winner}


def verdicts(summary: list[dict], episodes: list[dict], families: Mapping) -> list[dict]:
    """Per experiment: its best planner, best trained agent (sampled actions) and random's row;
    P(improvement) with its interval for RL over the planner, RL over random and the planner
    over random (`_compare`); and whether the experiment discriminates: whether the best of
    these rows improves on the worst (the lower bound of P above 0.5). An experiment that does
    not is left out of the headline table."""
    out = []
    for name in dict.fromkeys(r["experiment"] for r in summary):
        if name not in families:
            continue
        family = families[name]
        rows = [r for r in summary if r["experiment"] == name]
        planner, rl = _best(rows, family, "planner"), _best(rows, family, "rl")
        random = _best(rows, family, "random")
        shown = [r for r in (planner, rl, random)
                 if r is not None and r.get("seeds", stats.MIN_SEEDS) >= stats.MIN_SEEDS]
        spread = ordered(shown, family)
        apart = (_compare(spread[0], spread[-1], episodes, name, family)
                 if len(spread) > 1 else None)
        out.append({"experiment": name, "score": family.score,
                    "higher_is_better": family.higher_is_better, "planner": planner, "rl": rl,
                    "random": random,
                    "rl_vs_planner": _compare(rl, planner, episodes, name, family),
                    "rl_vs_random": _compare(rl, random, episodes, name, family),
                    "planner_vs_random": _compare(planner, random, episodes, name, family),
                    "discriminates": apart is not None and apart["winner"] is not None})
    return out


def verdict_text(comparison: dict | None) -> str:
    """``P=0.62 [0.58, 0.66]: <winner>`` (``no difference`` when undecided), ``-`` without a
    comparison."""
    if comparison is None:
        return "-"
    who = comparison["winner"] or "no difference"
    return f"P={comparison['p']:.2f} [{comparison['p_lo']:.2f}, {comparison['p_hi']:.2f}]: {who}"


#: the columns of the headline table and of ``verdicts.csv``
VERDICT_COLUMNS = ("experiment", "score", "direction", "planner", "rl", "random",
                   "rl_vs_planner", "rl_vs_random", "planner_vs_random", "discriminates")


def verdict_rows(verdict_list: list[dict]) -> list[dict]:
    """The verdicts as flat text rows (``verdicts.csv``, the headline tables of README.md and
    the docs: `bounce_gym_experiments.published`)."""
    def shown(row, score):
        return "-" if row is None else f"{row_name(row)}: {cell(row, score)}"

    return [{"experiment": v["experiment"], "score": v["score"],
             "direction": "higher" if v["higher_is_better"] else "lower",
             **{k: shown(v[k], v["score"]) for k in ("planner", "rl", "random")},
             **{k: verdict_text(v[k]) for k in ("rl_vs_planner", "rl_vs_random",
                                                "planner_vs_random")},
             "discriminates": "yes" if v["discriminates"] else "no"} for v in verdict_list]


def headline_markdown(rows: list[dict]) -> list[str]:
    """The "Who wins" table of verdict rows (`verdict_rows`): the experiments that
    discriminate, then one line naming those left out."""
    lines = ["| experiment | score | best planner | best trained agent | random | RL vs planner "
             "| RL vs random | planner vs random |", "|---|---|---|---|---|---|---|---|"]
    for v in rows:
        if v["discriminates"] == "yes":
            lines.append(f"| {v['experiment']} | {v['score']} ({v['direction']} is better) | "
                         f"{v['planner']} | {v['rl']} | {v['random']} | {v['rl_vs_planner']} | "
                         f"{v['rl_vs_random']} | {v['planner_vs_random']} |")
    left_out = [v["experiment"] for v in rows if v["discriminates"] != "yes"]
    if left_out:
        lines += ["", "Not in this table, because its best and worst compared rows are not apart "
                  f"on the score: {', '.join(left_out)}."]
    return lines


#: the widest line of `who_wins_text`
WHO_WINS_WIDTH = 100
#: how `who_wins_text` names the rows a verdict compares
_SHOWN_AS = {"planner": "planner", "rl": "RL", "random": "random"}


def winners(verdict: dict) -> list[str]:
    """The keys (``planner``, ``rl``, ``random``) of the rows of an experiment's verdict that
    beat at least one other and that none beats, by its comparisons (`verdicts`)."""
    beats: dict[str, set[str]] = {key: set() for key in _SHOWN_AS}
    for first, second in (("rl", "planner"), ("rl", "random"), ("planner", "random")):
        comparison = verdict[f"{first}_vs_{second}"]
        if comparison is None or comparison["winner"] is None:
            continue
        won, lost = ((first, second) if comparison["winner"] == verdict[first]["policy"]
                     else (second, first))
        beats[won].add(lost)
    beaten = set().union(*beats.values())
    return [key for key in _SHOWN_AS if beats[key] and key not in beaten]


def who_wins_text(verdict_list: list[dict], report: str) -> str:
    """The verdicts as plain text no wider than `WHO_WINS_WIDTH`: per experiment, its score
    and who wins (`winners`; "none apart" where no comparison decides), then each compared
    row's value with its 95% interval and count; ``report`` names where the full tables are."""
    lines = ["Who wins: per experiment, the best planner, the best trained agent (sampled actions)",
             "and random bouncing on its score: value [95% interval] n=episodes. The winner beats",
             "another by P(improvement) and none beats it. The rows' names, the P values and every",
             f"table: {report}"]
    for v in verdict_list:
        shown = [key for key in _SHOWN_AS if v[key] is not None]
        top = winners(v)
        verdict = (" and ".join(_SHOWN_AS[key] for key in top) if top
                   else "none apart" if len(shown) > 1 else "one row, nothing to compare")
        better = "higher" if v["higher_is_better"] else "lower"
        values = "; ".join(f"{_SHOWN_AS[key]} {cell(v[key], v['score'], small=2)}"
                           for key in shown)
        lines += ["", *textwrap.wrap(f"{v['experiment']}: {v['score']} ({better} is better); "
                                     f"winner: {verdict}", WHO_WINS_WIDTH,
                                     subsequent_indent="    "),
                  *textwrap.wrap(values, WHO_WINS_WIDTH, initial_indent="    ",
                                 subsequent_indent="    ")]
    return "\n".join(lines)


def _verdict_lines(rows: list[dict]) -> list[str]:
    lines = ["## Who wins", "",
             "Per experiment, the best planner, the best trained agent (sampled actions, at "
             f"least {stats.MIN_SEEDS} training seeds; the greedy rows are in the tables) and "
             "random bouncing on the task's score. Each comparison is the probability of "
             "improvement P(X > Y) — that an episode of the first scores better than one of the "
             "second — with its 95% interval; the first wins when the interval lies above 0.5, "
             "the second when it lies below. A row's name says what it observes beyond contact "
             "and clock.", ""]
    return lines + headline_markdown(rows) + [""]


def markdown(config: Mapping, summary: list[dict], verdict_list: list[dict], families: Mapping,
             notes: list[str], provenance: Mapping) -> str:
    """The leaderboard as Markdown (see the module); ``verdict_list``: its `verdict_rows`."""
    experiments = {exp["name"]: exp for exp in config["experiments"]}
    git = provenance.get("git", {})
    lines = [f"# {config['name']}: leaderboard", "",
             f"Commit {git.get('commit', 'unknown')}{' (modified)' if git.get('dirty') else ''}. "
             "Each cell: value [95% interval] n=episodes. A row is a list of runs (a trained "
             "algorithm: one per training seed; anything else: one); the value is the "
             "interquartile mean of the runs' means and the interval a bootstrap over runs and "
             "their episodes, for rates and means alike. Rows are ordered by each task's score; "
             "the order alone ranks nothing.",
             "", *_verdict_lines(verdict_list)]
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


def write_leaderboard(folder: Path, config: Mapping, summary: list[dict], verdict_list: list[dict],
                      families: Mapping, notes: list[str], provenance: Mapping) -> list[Path]:
    """Write ``leaderboard.md``, ``leaderboard.csv``, ``verdicts.csv`` (the headline rows,
    `verdict_rows`) and, unless the configuration draws no ``plots``, ``leaderboard.png``;
    returns them. ``verdict_list``: the `verdicts`."""
    md, table, verdict_file = (folder / "leaderboard.md", folder / "leaderboard.csv",
                               folder / "verdicts.csv")
    decided = verdict_rows(verdict_list)
    atomic_write(md, markdown(config, summary, decided, families, notes, provenance).encode())
    atomic_write(table, csv_text(csv_rows(config, summary, families),
                                 ("experiment", "difficulty", "env", "policy", "episodes",
                                  "seeds", "score")).encode())
    atomic_write(verdict_file, csv_text(decided, VERDICT_COLUMNS).encode())
    figure = plot(folder, summary, families) if config["plots"] else None
    return [md, table, verdict_file] + ([figure] if figure is not None else [])
