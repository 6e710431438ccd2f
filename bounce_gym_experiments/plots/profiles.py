"""Performance profiles of trained agents (Agarwal et al., NeurIPS 2021, Sec. 4): for every
threshold τ, the fraction of training runs whose score is above it, with a stratified-bootstrap
95% band (`bounce_gym_experiments.stats.performance_profile`). One figure per experiment with trained
models; the score is the family's (`bounce_gym_experiments.families.base.Family.score`)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from bounce_gym_experiments.plots.figures import pyplot, save_figure
from bounce_gym_experiments.stats import performance_profile


def plot_profiles(folder: Path, per_seed: list[dict], families: Mapping) -> list[Path]:
    """``<experiment>-profile.png`` for every experiment in ``per_seed`` (rows with ``group``,
    `bounce_gym_experiments.report.table_rows`) whose family's score they have."""
    by_experiment: dict[str, dict[str, list[float]]] = {}
    for row in per_seed:
        family = families.get(row["experiment"])
        if family is not None and row.get(family.score) is not None:
            runs = by_experiment.setdefault(row["experiment"], {})
            runs.setdefault(row["group"], []).append(float(row[family.score]))
    plt = pyplot()
    written = []
    for name, groups in by_experiment.items():
        family = families[name]
        sign = 1.0 if family.higher_is_better else -1.0
        values = np.concatenate([np.asarray(v) for v in groups.values()])
        lo, hi = float(values.min()), float(values.max())
        pad = 0.05 * (hi - lo) if hi > lo else max(abs(lo), 1.0) * 0.05
        taus = np.linspace(lo - pad, hi + pad, 101)
        fig, ax = plt.subplots(figsize=(4.2, 3.0))
        for group, runs in groups.items():
            profile = performance_profile(sign * np.asarray(runs), sign * taus)
            line, = ax.plot(taus, profile.fraction, label=f"{group} ({len(runs)} seeds)")
            ax.fill_between(taus, profile.lo, profile.hi, color=line.get_color(), alpha=0.2,
                            step=None)
        relation = ">" if family.higher_is_better else "<"
        ax.set_xlabel(f"τ ({family.score} per training seed)")
        ax.set_ylabel(f"fraction of runs with {family.score} {relation} τ")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(f"{name}: performance profile, 95% CI", fontsize=9)
        ax.legend(fontsize=7)
        written.append(save_figure(fig, folder / f"{name}-profile.png"))
    return written
