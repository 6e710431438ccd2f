"""Figures for the bounce visibility graph of Nilles et al. (2021): the partition P', G_safe,
the cone of trajectories of a plan and a limit cycle. Every function renders with matplotlib
(Agg), writes the PNG atomically (`bounce_gym_experiments.plots.figures.save_figure`) and returns its
path."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import networkx as nx  # noqa: E402
import numpy as np  # noqa: E402

from baselines.visibility.partition import Partition  # noqa: E402
from bounce_gym_experiments.plots.figures import save_figure  # noqa: E402

__all__ = ["plot_limit_cycle", "plot_partition", "plot_plan_cone", "plot_safe_graph"]


def _draw_boundary(ax, part: Partition, labels: bool = True, highlight=()) -> None:
    for k in range(part.n):
        a, b = part.start[k], part.end[k]
        colour = "#d62728" if k in highlight else "#333333"
        ax.plot([a[0], b[0]], [a[1], b[1]], color=colour, lw=2.0 if k in highlight else 1.2)
        if labels:
            mid = 0.5 * (a + b) + 0.02 * part.world.diameter * part.normal[k]
            ax.text(mid[0], mid[1], str(k), fontsize=7, ha="center", va="center",
                    color=colour)
    ax.plot(part.start[:, 0], part.start[:, 1], "o", ms=2.5,
            color="#1f77b4")
    ins = part.start[part.inserted]
    ax.plot(ins[:, 0], ins[:, 1], "o", ms=3.5, mfc="none", color="#ff7f0e")
    ax.set_aspect("equal")
    ax.axis("off")


def plot_partition(part: Partition, path: Path | str, title: str | None = None) -> Path:
    """P' with segment ids (inserted vertices circled)."""
    fig, ax = plt.subplots(figsize=(6, 4.5))
    _draw_boundary(ax, part)
    ax.set_title(title or f"P': {part.n} segments", fontsize=9)
    return save_figure(fig, path)


def plot_safe_graph(g: nx.DiGraph, path: Path | str, title: str | None = None) -> Path:
    """G_safe drawn with networkx (circular layout; arc shade = interval width)."""
    fig, ax = plt.subplots(figsize=(6, 6))
    pos = nx.circular_layout(sorted(g.nodes))
    widths = [g.edges[e].get("width", 1.0) for e in g.edges]
    nx.draw_networkx_nodes(g, pos, ax=ax, node_size=180, node_color="#cfe2ff")
    nx.draw_networkx_labels(g, pos, ax=ax, font_size=7)
    if g.number_of_edges():
        nx.draw_networkx_edges(g, pos, ax=ax, edge_color=widths, edge_cmap=plt.cm.viridis,
                               arrowsize=7, width=0.8, node_size=180,
                               connectionstyle="arc3,rad=0.08")
    ax.set_title(title or f"G_safe: {g.number_of_nodes()} nodes, {g.number_of_edges()} arcs",
                 fontsize=9)
    ax.axis("off")
    return save_figure(fig, path)


def plot_plan_cone(part: Partition, plan, path: Path | str, n_rays: int = 100, seed: int = 0,
                   title: str | None = None) -> Path:
    """The cone of trajectories of a `VisibilityPlan`: ``n_rays`` sampled runs (uniform start on
    the start segment(s), θ uniform strictly inside each stage's interval), by ray casting."""
    rng = np.random.default_rng(seed)
    world = part.world
    starts = np.asarray(plan.stages[0])
    seg = starts[rng.choice(len(starts), size=n_rays, p=part.length[starts]
                            / part.length[starts].sum())]
    frac = rng.uniform(1e-9, 1 - 1e-9, size=n_rays)
    pts = part.start[seg] + (frac * part.length[seg])[:, None] * part.tangent[seg]
    edge = part.edge[seg]
    trail = [pts]
    for lo, hi in plan.intervals:
        w = hi - lo
        theta = rng.uniform(lo + 1e-9 * w, hi - 1e-9 * w, size=n_rays)
        d = (np.cos(theta)[:, None] * world.tangents[edge]
             + np.sin(theta)[:, None] * world.normals[edge])
        hits = world.first_hit(pts, d)
        dist = np.where(hits.edge >= 0, hits.distance, 0.0)
        pts = pts + dist[:, None] * d
        edge = np.where(hits.edge >= 0, hits.edge, edge)
        trail.append(pts)
    trail = np.stack(trail, axis=1)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    highlight = {k for s in plan.stages for k in s}
    _draw_boundary(ax, part, highlight=highlight)
    for r in trail:
        ax.plot(r[:, 0], r[:, 1], color="#2ca02c", lw=0.5, alpha=0.35)
    label = " → ".join("/".join(map(str, s)) for s in plan.stages)
    ax.set_title(title or f"{plan.kind} plan {label}", fontsize=9)
    return save_figure(fig, path)


def plot_limit_cycle(part: Partition, cycle, path: Path | str, title: str | None = None) -> Path:
    """A limit cycle: a `PatrolPlan` or a `CompositeCycle` (its contact points joined in order)."""
    fixed = getattr(cycle, "fixed_point", cycle)
    pts = np.asarray(fixed.points)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    highlight = set(getattr(cycle, "cycle", ()))
    _draw_boundary(ax, part, highlight=highlight)
    closed = np.vstack([pts, pts[:1]])
    ax.plot(closed[:, 0], closed[:, 1], "-", color="#9467bd", lw=1.5)
    ax.plot(pts[:, 0], pts[:, 1], "o", color="#9467bd", ms=4)
    ax.set_title(title or f"limit cycle, C(F) = {fixed.coefficient:.3g}", fontsize=9)
    return save_figure(fig, path)
