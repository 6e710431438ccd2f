"""Figures of the patrol evaluation (Alam 2018, thesis ch. 4): MAECT edge weights on the map
(as Fig. 4.6 draws them), the per-robot visibility covers (Alg. 4.3), and p_d(t_a) curves, the
fitted generalised lambda distribution beside the empirical CDF (as Tables 4.6/4.7 tabulate
them). Maps are drawn on the cell graph's centres (x east, y north). Every function renders with
matplotlib (Agg), writes the PNG atomically (`bounce_gym_experiments.plots.figures.save_figure`) and
returns its path."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import networkx as nx
import numpy as np

from baselines.patrolling.vulnerability import DetectionCurve
from bounce_gym_experiments.plots.figures import pyplot, save_figure

__all__ = ["plot_covers", "plot_detection_curves", "plot_edge_weights"]

_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
            "#17becf")


def _positions(graph: nx.Graph) -> np.ndarray:
    return np.array([graph.nodes[v]["pos"] for v in graph], dtype=np.float64)


def _draw_cells(ax, graph: nx.Graph, colours=None) -> None:
    xy = _positions(graph)
    size = float(graph.graph.get("cell_size", 1.0))
    ax.scatter(xy[:, 0], xy[:, 1], s=(110 * size) ** 1, marker="s",
               c="#eeeeee" if colours is None else colours, linewidths=0)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def plot_edge_weights(graph: nx.Graph, weights: Mapping, path: Path | str,
                      title: str | None = None) -> Path:
    """Every edge drawn with a width and shade in proportion to its MAECT weight."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    _draw_cells(ax, graph)
    largest = max(weights.values()) or 1.0
    cmap = plt.get_cmap("viridis")
    for (u, v), w in sorted(weights.items(), key=lambda item: item[1]):
        (x0, y0), (x1, y1) = graph.nodes[u]["pos"], graph.nodes[v]["pos"]
        share = w / largest
        ax.plot([x0, x1], [y0, y1], color=cmap(share), lw=0.3 + 3.0 * share,
                solid_capstyle="round")
    mappable = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0.0, largest))
    fig.colorbar(mappable, ax=ax, shrink=0.7, label="edge weight w_e")
    ax.set_title(title or "MAECT edge weights", fontsize=9)
    return save_figure(fig, path)


def plot_covers(graph: nx.Graph, seen, covers: Sequence[Sequence[int]], path: Path | str,
                title: str | None = None) -> Path:
    """One panel per robot: its cover's viewing cells (stars) and, shaded, how many of them see
    each cell. ``seen``: the (n, n) visibility matrix, entry (z, c) iff z sees c."""
    plt = pyplot()
    seen = seen.tocsr() if hasattr(seen, "tocsr") else np.asarray(seen)
    xy = _positions(graph)
    fig, axes = plt.subplots(1, len(covers), figsize=(3.6 * len(covers), 3.8), squeeze=False)
    for i, (ax, cover) in enumerate(zip(axes[0], covers, strict=True)):
        count = np.asarray(seen[list(cover)].sum(axis=0)).ravel()
        _draw_cells(ax, graph, colours=plt.get_cmap("Blues")(0.15 + 0.6 * count
                                                             / max(count.max(), 1)))
        ax.plot(xy[cover, 0], xy[cover, 1], "*", color=_COLOURS[i % len(_COLOURS)], ms=10,
                mec="k", mew=0.5)
        ax.set_title(f"robot {i + 1}: {len(cover)} viewing cells", fontsize=8)
    fig.suptitle(title or "visibility covers (Alg. 4.3)", fontsize=9)
    return save_figure(fig, path)


def plot_detection_curves(curves: Mapping[str, DetectionCurve], path: Path | str,
                          measured: Mapping[str, tuple[float, float, float, float]] | None = None,
                          title: str | None = None) -> Path:
    """p_d(t_a) per strategy: the fitted GλD's CDF (line) beside the empirical CDF (steps);
    ``measured``: per strategy (t_a, rate, lo, hi), the capture rate of the evaluation with its
    95% interval (a point with an error bar)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.8, 3.8))
    for k, (name, curve) in enumerate(curves.items()):
        colour = _COLOURS[k % len(_COLOURS)]
        fitted = np.isfinite(curve.fitted).any()
        if fitted:
            ax.plot(curve.t_a, curve.fitted, color=colour, lw=1.5, label=f"{name} (GλD fit)")
        ax.step(curve.t_a, curve.empirical, where="post", color=colour, lw=0.8, ls="--",
                label=None if fitted else f"{name} (empirical; nothing to fit)")
        if measured and name in measured:
            t_a, rate, lo, hi = measured[name]
            shift = (k - (len(curves) - 1) / 2) * 0.01 * float(np.ptp(curve.t_a))  # side by side
            ax.errorbar([t_a + shift], [rate], yerr=[[rate - lo], [hi - rate]], fmt="o",
                        color=colour, capsize=3, ms=4)
    ax.set_xlabel("attack time t_a (steps)")
    ax.set_ylabel("p_d(t_a)")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(title or "p_d(t_a): GλD fit (line), empirical CDF (dashed)", fontsize=9)
    return save_figure(fig, path)
