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


def format_table(summary: list[dict]) -> str:
    """A plain-text table of the per-(experiment, policy) means."""
    columns = ["experiment", "policy", "episodes", "return", "ticks", "success",
               "ticks_to_goal", "predicted_ticks", "predicted_weight", "coverage", "distance", "candidates"]
    present = [c for c in columns if any(c in row for row in summary)]

    def cell(value) -> str:
        if value is None:
            return "-"
        if isinstance(value, float):
            return f"{value:.3f}" if abs(value) < 1000 else f"{value:.0f}"
        return str(value)

    rows = [[cell(r.get(c)) for c in present] for r in summary]
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


def write_plots(folder: Path, plots: dict) -> list[Path]:
    """Trajectories per experiment; coverage heatmaps vs the target; mixture weights α."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    for name, data in plots.items():
        world = data["world"]
        policies = list(data["paths"])
        fig, axes = plt.subplots(1, len(policies), figsize=(3.2 * len(policies), 3.0),
                                 squeeze=False)
        for ax, policy in zip(axes[0], policies, strict=True):
            for ring in world.rings:
                closed = np.vstack([ring, ring[:1]])
                ax.plot(closed[:, 0], closed[:, 1], color="#223", lw=1.5)
            path = data["paths"][policy]
            ax.plot(path[:, 0], path[:, 1], lw=0.8, color="#2a6fdb")
            ax.plot(*path[0], "o", color="#1a9850", ms=4, label="start")
            ax.plot(*path[-1], "x", color="#d73027", ms=5, label="end")
            ax.set_title(policy, fontsize=8)
            ax.set_aspect("equal")
            ax.axis("off")
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
            from baselines.visibility import plots as vis

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
