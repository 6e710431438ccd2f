"""Writing evaluation results: the printed table, CSV and JSON files, and plots."""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path

import numpy as np


def atomic_write(path: Path, data: bytes) -> None:
    """Write a file so that readers never see it half-written."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes files private; results are not
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


SINGLE_COLUMNS = ["experiment", "policy", "episodes", "return", "ticks", "success",
                  "ticks_to_goal", "predicted_ticks", "predicted_weight", "coverage", "distance",
                  "candidates"]
MULTI_COVERAGE_COLUMNS = ["experiment", "policy", "robots", "episodes", "full", "steps_to_full",
                          "predicted_steps_to_full", "coverage", "ticks", "robot_contacts"]
MULTI_MONITORING_COLUMNS = ["experiment", "policy", "robots", "episodes", "in_region",
                            "encounters", "robot_contacts", "r", "period", "ticks"]
#: multi-robot columns printed as "mean ± std"
SPREAD = {"steps_to_full", "predicted_steps_to_full", "coverage", "ticks", "robot_contacts",
          "in_region", "encounters"}


def format_table(summary: list[dict]) -> str:
    """Plain-text tables of the per-(experiment, policy) summary: single-robot means; for
    multi-robot coverage and monitoring experiments (rows with ``robots``) mean ± std, and the
    episodes that reached full coverage as ``full``/``episodes``."""
    families = [
        ("", SINGLE_COLUMNS, [r for r in summary if "robots" not in r]),
        ("multi-robot coverage", MULTI_COVERAGE_COLUMNS,
         [r for r in summary if "robots" in r and "full" in r]),
        ("multi-robot monitoring", MULTI_MONITORING_COLUMNS,
         [r for r in summary if "robots" in r and "full" not in r]),
    ]
    blocks = [(title + "\n" if title else "") + _table(columns, rows, spread=bool(title))
              for title, columns, rows in families if rows]
    return "\n\n".join(blocks)


def _table(columns: list[str], summary: list[dict], spread: bool) -> str:
    present = [c for c in columns if any(c in row for row in summary)]

    def number(value) -> str:
        if isinstance(value, float):
            return f"{value:.3f}" if abs(value) < 1000 else f"{value:.0f}"
        return str(value)

    def cell(row: dict, column: str) -> str:
        value = row.get(column)
        if value is None:
            return "-"
        if column == "full":
            return f"{value}/{row['episodes']}"
        if spread and column in SPREAD and f"{column}_std" in row:
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


def write_plots(folder: Path, plots: dict, summary: list[dict] | None = None) -> list[Path]:
    """Trajectories per experiment; coverage heatmaps vs the target; mixture weights α; for
    multi-robot experiments every robot's trajectory, visit heatmaps and — given the summary —
    steps to full coverage against the number of robots."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    for name, data in plots.items():
        if data.get("multi"):
            written += _multi_plots(folder, name, data)
            continue
        world = data["world"]
        policies = list(data["paths"])
        fig, axes = plt.subplots(1, len(policies), figsize=(3.2 * len(policies), 3.0),
                                 squeeze=False)
        for ax, policy in zip(axes[0], policies, strict=True):
            _draw_world(ax, world)
            path = data["paths"][policy]
            ax.plot(path[:, 0], path[:, 1], lw=0.8, color="#2a6fdb")
            ax.plot(*path[0], "o", color="#1a9850", ms=4, label="start")
            ax.plot(*path[-1], "x", color="#d73027", ms=5, label="end")
            ax.set_title(policy, fontsize=8)
        fig.suptitle(f"{name}: trajectories (first seed)", fontsize=9)
        written.append(save_figure(fig, folder / f"{name}-trajectories.png"))
        if data["coverage"]:
            items = [("target", data["target"])] + [
                (p, v / max(v.sum(), 1e-12)) for p, v in data["coverage"].items()]
            fig, axes = plt.subplots(1, len(items), figsize=(3.0 * len(items), 2.8),
                                     squeeze=False)
            # a shared scale, capped so that one concentrated policy does not blacken the rest
            top = 4 * float(np.max(data["target"]))
            for ax, (label, values) in zip(axes[0], items, strict=True):
                ax.imshow(values, origin="lower", vmin=0, vmax=top, cmap="magma")
                ax.set_title(label, fontsize=8)
                ax.axis("off")
            fig.suptitle(f"{name}: time spent per cell vs target (first seed)", fontsize=9)
            written.append(save_figure(fig, folder / f"{name}-coverage.png"))
        scenario = data.get("visibility")
        if scenario is not None:
            from experiments.plots import visibility as vis

            written += [
                vis.plot_partition(scenario.part, folder / f"{name}-partition.png",
                                   title=f"{name}: P' with segment ids"),
                vis.plot_safe_graph(scenario.graph, folder / f"{name}-safe-graph.png",
                                    title=f"{name}: safe graph"),
            ]
            if scenario.goal is None:
                written.append(vis.plot_limit_cycle(scenario.part, scenario.plan,
                                                    folder / f"{name}-limit-cycle.png",
                                                    title=f"{name}: patrolled limit cycle"))
            else:
                written.append(vis.plot_plan_cone(
                    scenario.part, scenario.plan, folder / f"{name}-plan.png",
                    title=f"{name}: {scenario.plan.kind} plan {scenario.start}→{scenario.goal}"))
        if "alpha" in data:
            alpha, degrees = data["alpha"]
            fig, ax = plt.subplots(figsize=(3.5, 2.5))
            ax.bar([f"{d:g}°" for d in degrees], alpha, color="#2a6fdb")
            ax.set_ylabel("α (share of time)")
            ax.set_title(f"{name}: optimal policy mixture", fontsize=9)
            written.append(save_figure(fig, folder / f"{name}-alpha.png"))
    if summary is not None:
        written += _steps_vs_robots(folder, plots, summary)
    return written


def _draw_world(ax, world) -> None:
    for ring in world.rings:
        closed = np.vstack([ring, ring[:1]])
        ax.plot(closed[:, 0], closed[:, 1], color="#223", lw=1.5)
    ax.set_aspect("equal")
    ax.axis("off")


def _multi_plots(folder: Path, name: str, data: dict) -> list[Path]:
    """A multi-robot experiment's first-seed trajectories (one colour per robot, monitoring
    regions shaded) and, for coverage, the visit counts per cell."""
    import matplotlib.pyplot as plt

    written = []
    policies = list(data["paths"])
    fig, axes = plt.subplots(1, len(policies), figsize=(3.2 * len(policies), 3.0), squeeze=False)
    colours = plt.get_cmap("tab10")
    for ax, policy in zip(axes[0], policies, strict=True):
        for k, ring in enumerate(data.get("regions") or []):
            ax.fill(ring[:, 0], ring[:, 1], color=colours(k % 10), alpha=0.12)
        _draw_world(ax, data["world"])
        path = data["paths"][policy]  # (steps + 1, m, 2)
        for i in range(path.shape[1]):
            ax.plot(path[:, i, 0], path[:, i, 1], lw=0.6, alpha=0.7, color=colours(i % 10))
            ax.plot(*path[0, i], "o", color=colours(i % 10), ms=3)
        ax.set_title(f"{policy} ({len(path) - 1} steps)", fontsize=8)
    fig.suptitle(f"{name}: trajectories (first seed)", fontsize=9)
    written.append(save_figure(fig, folder / f"{name}-trajectories.png"))
    if data["visits"]:
        items = list(data["visits"].items())
        fig, axes = plt.subplots(1, len(items), figsize=(3.0 * len(items), 2.8), squeeze=False)
        for ax, (policy, visits) in zip(axes[0], items, strict=True):
            shown = np.where(data["free"], np.log1p(visits), np.nan)  # blocked cells blank
            ax.imshow(shown, origin="lower", cmap="magma")
            ax.set_title(f"{policy}: {np.count_nonzero(visits)} cells", fontsize=8)
            ax.axis("off")
        fig.suptitle(f"{name}: log(1 + ticks) per cell (first seed)", fontsize=9)
        written.append(save_figure(fig, folder / f"{name}-visits.png"))
    return written


def _steps_vs_robots(folder: Path, plots: dict, summary: list[dict]) -> list[Path]:
    """Steps to full coverage (mean ± std over the episodes that reached it) against the number
    of robots, one figure per (world, backend) with at least two team sizes."""
    import matplotlib.pyplot as plt

    by_world: dict[str, list[dict]] = {}
    for row in summary:
        data = plots.get(row["experiment"], {})
        if data.get("multi") and row.get("steps_to_full") is not None:
            key = f"{data['world'].name}-{data['backend']}"
            by_world.setdefault(key, []).append(row)
    written = []
    for world, rows in by_world.items():
        if len({r["robots"] for r in rows}) < 2:
            continue
        fig, ax = plt.subplots(figsize=(4.2, 3.0))
        for policy in dict.fromkeys(r["policy"] for r in rows):
            mine = sorted((r for r in rows if r["policy"] == policy), key=lambda r: r["robots"])
            ax.errorbar([r["robots"] for r in mine], [r["steps_to_full"] for r in mine],
                        yerr=[r["steps_to_full_std"] for r in mine], marker="o", capsize=3,
                        label=policy)
        ax.set_xticks(sorted({r["robots"] for r in rows}))
        ax.set_xlabel("robots m")
        ax.set_ylabel("steps to full coverage")
        ax.set_title(f"{world}: mean ± std over covered episodes", fontsize=9)
        ax.legend(fontsize=7)
        written.append(save_figure(fig, folder / f"steps-vs-robots-{world}.png"))
    return written


def save_figure(fig, path: Path | str) -> Path:
    """Save a matplotlib figure as a PNG atomically and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(path, buf.getvalue())
    return path
