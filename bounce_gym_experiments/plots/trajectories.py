"""Every experiment's first-seed trajectories, one panel per policy and one colour per robot
(shaded regions where the task has them)."""

from __future__ import annotations

from pathlib import Path

from bounce_gym_experiments.plots.figures import draw_world, pyplot, save_figure


def plot_trajectories(folder: Path, name: str, data: dict) -> list[Path]:
    """``data``: ``world``, ``paths`` (policy → positions (steps + 1, m, 2)) and optionally
    ``regions`` (rings to shade). Writes ``<name>-trajectories.png``."""
    plt = pyplot()
    policies = list(data["paths"])
    if not policies:
        return []
    fig, axes = plt.subplots(1, len(policies), figsize=(3.2 * len(policies), 3.0), squeeze=False)
    colours = plt.get_cmap("tab10")
    for ax, policy in zip(axes[0], policies, strict=True):
        for k, ring in enumerate(data.get("regions") or []):
            ax.fill(ring[:, 0], ring[:, 1], color=colours(k % 10), alpha=0.12)
        draw_world(ax, data["world"])
        path = data["paths"][policy]
        for i in range(path.shape[1]):
            ax.plot(path[:, i, 0], path[:, i, 1], lw=0.7, alpha=0.8, color=colours(i % 10))
            ax.plot(*path[0, i], "o", color=colours(i % 10), ms=3)
            ax.plot(*path[-1, i], "x", color=colours(i % 10), ms=4)
        ax.set_title(f"{policy} ({len(path) - 1} steps)", fontsize=8)
    fig.suptitle(f"{name}: trajectories (first seed)", fontsize=9)
    return [save_figure(fig, folder / f"{name}-trajectories.png")]
