"""Learning-curve figure and table of a models folder (`baselines.rl.curves`).

``learning_curves.png``: one panel per metric (return, success, …) against env steps; per run
(``ppo``, ``ppo-stack4``, …) one colour, a thin line per seed, the mean across seeds in bold and
its 95% confidence interval shaded (a seed's line drawn through at most `SEED_POINTS` of its
episodes, evenly spaced, its last included). ``learning_curves.csv``: the end point of every
seed (episodes, env steps, each metric's moving mean over the last episodes).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from baselines.rl.curves import WINDOW, RunCurves, learning_curves
from bounce_gym.files import atomic_write
from bounce_gym_experiments.plots.figures import pyplot, save_figure

#: The most points of a seed's line in the figure (a few per pixel of a panel).
SEED_POINTS = 4000


def write_learning_curves(folder: Path, window: int = WINDOW) -> tuple[list[Path], list[str]]:
    """Write the figure and the table into ``folder``; returns their paths and the lines of a
    printable summary (per run: seeds, env steps and each metric's mean [95% CI] at the end);
    nothing if no episode has finished yet."""
    runs = learning_curves(folder, window)
    if not runs:
        return [], []
    return ([plot_learning_curves(runs, folder / "learning_curves.png", window),
             write_end_points(runs, folder / "learning_curves.csv")], summary_lines(runs))


def plot_learning_curves(runs: list[RunCurves], path: Path, window: int) -> Path:
    plt = pyplot()
    metrics = list(dict.fromkeys(m for run in runs for m in run.metrics))
    fig, axes = plt.subplots(1, len(metrics), figsize=(5.5 * len(metrics), 4), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, metric in zip(axes[0], metrics, strict=True):
        for k, run in enumerate(runs):
            if metric not in run.metrics:
                continue
            colour = colours[k % len(colours)]
            for columns in run.seeds.values():
                shown = _spaced(len(columns["steps"]), SEED_POINTS)
                ax.plot(columns["steps"][shown], columns[metric][shown], color=colour, lw=0.6,
                        alpha=0.45)
            steps, mean, low, high = run.across_seeds(metric)
            ax.plot(steps, mean, color=colour, lw=2,
                    label=f"{run.name} ({len(run.seeds)} seeds)" if len(run.seeds) > 1
                    else f"{run.name} (1 seed)")
            if len(run.seeds) > 1:
                ax.fill_between(steps, low, high, color=colour, alpha=0.2, lw=0)
        ax.set_xlabel("env steps")
        ax.set_ylabel(f"{metric} (mean of the last {window} episodes)")
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f"{path.parent.name}: thin lines seeds, bold mean, band 95% CI of the mean",
                 fontsize=10)
    return save_figure(fig, path)


def _spaced(n: int, most: int) -> np.ndarray:
    """At most ``most`` indices of ``n``, evenly spaced, the first and the last included."""
    return np.unique(np.linspace(0, n - 1, min(n, most)).round().astype(int))


def write_end_points(runs: list[RunCurves], path: Path) -> Path:
    metrics = list(dict.fromkeys(m for run in runs for m in run.metrics))
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["run", "seed", "episodes", "env_steps", *metrics])
    for run in runs:
        for seed in run.seeds:
            final = run.final(seed)
            writer.writerow([run.name, seed, final["episodes"], final["env_steps"],
                             *(f"{final[m]:.6g}" if m in final else "" for m in metrics)])
    atomic_write(path, out.getvalue().encode())
    return path


def summary_lines(runs: list[RunCurves]) -> list[str]:
    lines = []
    for run in runs:
        parts = []
        for metric in run.metrics:
            _, mean, low, high = run.across_seeds(metric)
            ci = f" [{low[-1]:.3g}, {high[-1]:.3g}]" if np.isfinite(low[-1]) else ""
            parts.append(f"{metric} {mean[-1]:.3g}{ci}")
        steps = min(run.final(seed)["env_steps"] for seed in run.seeds)
        seeds = f"{len(run.seeds)} seed{'s' if len(run.seeds) > 1 else ''}"
        lines.append(f"{run.name}: {seeds}, at {steps} env steps: " + ", ".join(parts))
    return lines
