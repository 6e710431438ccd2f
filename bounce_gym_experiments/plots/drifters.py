"""Figures of the drifter planners (Alam 2018, thesis ch. 5, Figs. 5.6-5.16): the flow field,
persistent groups and their basins, absorption times, deployment cells, the visibility cover,
reachable sets and the value-iteration policy; and of their evaluation: drifter paths, and
coverage against steps with its interval band.

Maps are drawn on the cell grid (column i east, row j north, one unit per cell), land grey.
Every function renders with matplotlib (Agg), writes the PNG atomically
(`bounce_gym_experiments.plots.figures.save_figure`) and returns its path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from baselines.drifters import (
    Deployment,
    DrifterReachability,
    PersistentBehavior,
    ValueIterationResult,
    VisibilityDeployment,
)
from bounce_gym.cells import DOWN, DRIFT, UP, DrifterCells
from bounce_gym.flows import FlowField
from bounce_gym_experiments.plots.figures import pyplot, save_figure

__all__ = ["plot_absorption_times", "plot_behavior", "plot_coverage_curves", "plot_deployment",
           "plot_flow", "plot_paths", "plot_policy", "plot_reachability",
           "plot_visibility_deployment"]

_LAND = "#bdbdbd"
_GROUP_COLOURS = ("#2ca02c", "#d62728", "#1f77b4", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
                  "#17becf", "#bcbd22", "#7f7f7f")


def _layer_image(model: DrifterCells, layer: int, values, fill=np.nan) -> np.ndarray:
    """(Ny, Nx) float image of per-state ``values`` (over the layer's states) with ``fill`` on
    land."""
    index = model.index[layer]
    out = np.full(index.shape, fill, dtype=np.float64)
    water = index >= 0
    out[water] = np.asarray(values, dtype=np.float64)[index[water] - model.offsets[layer]]
    return out


def _draw_land(ax, land: np.ndarray) -> None:
    from matplotlib.colors import ListedColormap

    ax.imshow(np.where(land, 1.0, np.nan), origin="lower", cmap=ListedColormap([_LAND]),
              interpolation="nearest")
    ax.set_xlim(-0.5, land.shape[1] - 0.5)
    ax.set_ylim(-0.5, land.shape[0] - 0.5)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def _mark(ax, model: DrifterCells, states, **style) -> None:
    cells = model.cells[np.asarray(states, dtype=np.int64)]
    ax.plot(cells[:, 2], cells[:, 1], linestyle="none", **style)


def plot_flow(field: FlowField, path: Path | str, layer: int = 0, t: float | None = None,
              title: str | None = None) -> Path:
    """The currents of one layer at time ``t`` as arrows on the cell grid (thesis Fig. 5.6a),
    coloured by speed."""
    plt = pyplot()
    u, v = field.snapshot(t, "hold")
    u, v = u[layer], v[layer]
    dx, dy = field.metric_spacing()
    cu, cv = u / dx, v / dy  # cells per second: directions on the drawn grid
    speed = np.hypot(u, v)
    land = field.land[layer]
    fig, ax = plt.subplots(figsize=(6.5, 5))
    _draw_land(ax, land)
    jj, ii = np.nonzero(~land)
    norm = np.hypot(cu, cv)[jj, ii]
    norm[norm == 0] = 1.0
    arrows = ax.quiver(ii, jj, cu[jj, ii] / norm, cv[jj, ii] / norm, speed[jj, ii],
                       cmap="viridis", scale=35, width=0.004)
    fig.colorbar(arrows, ax=ax, shrink=0.8, label="speed [m/s]")
    ax.set_title(title or f"{field.name}: layer {layer} (depth {field.depth[layer]:g} m)",
                 fontsize=9)
    return save_figure(fig, path)


def _behavior_image(model: DrifterCells, behavior: PersistentBehavior) -> tuple:
    """RGBA image: persistent groups in full colour, single-domicile basins in a light shade of
    their group's colour, multiple-domicile regions in purple shades."""
    from matplotlib.colors import to_rgba

    rgba = np.zeros(behavior.n_cells * 4).reshape(behavior.n_cells, 4)
    labels = []
    for g in range(len(behavior.groups)):
        colour = _GROUP_COLOURS[g % len(_GROUP_COLOURS)]
        rgba[behavior.group_of == g] = to_rgba(colour)
        labels.append((to_rgba(colour), f"persistent group {g} ({len(behavior.groups[g])})"))
    for k, (key, cells) in enumerate(behavior.transient_groups.items()):
        if len(key) == 1:
            colour = to_rgba(_GROUP_COLOURS[next(iter(key)) % len(_GROUP_COLOURS)], 0.35)
        else:
            colour = to_rgba("#9467bd", 0.3 + 0.5 * (k % 3) / 2)
        rgba[cells - behavior.offset] = colour
        name = ",".join(str(g) for g in sorted(key))
        labels.append((colour, f"B({name}) ({len(cells)})"))
    index = model.index[behavior.layer]
    image = np.zeros(index.shape + (4,))
    water = index >= 0
    image[water] = rgba[index[water] - behavior.offset]
    return image, labels


def _draw_behavior(ax, model: DrifterCells, behavior: PersistentBehavior) -> None:
    from matplotlib.patches import Patch

    _draw_land(ax, model.index[behavior.layer] < 0)
    image, labels = _behavior_image(model, behavior)
    ax.imshow(image, origin="lower", interpolation="nearest")
    ax.legend(handles=[Patch(color=c, label=text) for c, text in labels], fontsize=7,
              loc="upper left", bbox_to_anchor=(1.01, 1.0))


def plot_behavior(model: DrifterCells, behavior: PersistentBehavior, path: Path | str,
                  title: str | None = None) -> Path:
    """Persistent groups and transient groups by domicile set (thesis Fig. 5.7a)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 5))
    _draw_behavior(ax, model, behavior)
    ax.set_title(title or f"Alg. 5.1, layer {behavior.layer}: {len(behavior.groups)} persistent "
                 f"and {len(behavior.transient_groups)} transient groups", fontsize=9)
    return save_figure(fig, path)


def plot_absorption_times(model: DrifterCells, behavior: PersistentBehavior, path: Path | str,
                          title: str | None = None) -> Path:
    """Expected absorption times (Eq. 5.7) on the map, and their spread per transient group
    (thesis Fig. 5.8)."""
    plt = pyplot()
    fig, (ax, box) = plt.subplots(1, 2, figsize=(11, 4.5),
                                  gridspec_kw={"width_ratios": [1.5, 1]})
    _draw_land(ax, model.index[behavior.layer] < 0)
    times = np.where(behavior.persistent, np.nan, behavior.absorption_time)
    shown = ax.imshow(_layer_image(model, behavior.layer, times), origin="lower",
                      interpolation="nearest", cmap="magma_r")
    fig.colorbar(shown, ax=ax, shrink=0.8, label="expected absorption time [steps]")
    ax.set_title(title or f"absorption times, layer {behavior.layer}", fontsize=9)
    groups = list(behavior.transient_groups.items())
    if groups:
        box.boxplot([behavior.absorption_time[cells - behavior.offset] for _, cells in groups],
                    showmeans=True)
        box.set_xticks(range(1, len(groups) + 1),
                       ["B(" + ",".join(str(g) for g in sorted(k)) + ")" for k, _ in groups],
                       fontsize=8)
    box.set_ylabel("steps")
    box.set_title("per transient group (mean = triangle)", fontsize=9)
    return save_figure(fig, path)


def plot_deployment(model: DrifterCells, behavior: PersistentBehavior,
                    deployments: dict[str, Deployment], path: Path | str,
                    title: str | None = None) -> Path:
    """Deployment cells over the persistent behaviour (thesis Fig. 5.7b); ``deployments`` maps a
    label to a `Deployment` (e.g. Alg. 5.2 and its baselines), drawn with different markers."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 5))
    _draw_behavior(ax, model, behavior)
    handles = list(ax.get_legend().legend_handles)
    for (label, dep), marker in zip(deployments.items(), "osD^v", strict=False):
        _mark(ax, model, dep.states, marker=marker, markersize=8, markerfacecolor="none",
              markeredgecolor="black", markeredgewidth=1.5, label=f"{label} ({len(dep)})")
    handles += ax.get_legend_handles_labels()[0]
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(title or "deployment cells", fontsize=9)
    return save_figure(fig, path)


def plot_visibility_deployment(model: DrifterCells, result: VisibilityDeployment,
                               path: Path | str, title: str | None = None) -> Path:
    """The greedy cover 𝒟 (circles) and the deployment cells 𝒞 kept from it (filled) over the
    seafloor, shaded by how many cover cells see each seafloor cell (thesis Fig. 5.9)."""
    from baselines.drifters import visible_cells

    plt = pyplot()
    floor = int(model.cells[result.seafloor[0], 0])
    layer = int(model.cells[result.cover[0], 0])
    seen = visible_cells(model, result.d, layer, floor, result.rule)
    count = np.asarray(seen[result.cover - model.offsets[layer]].sum(axis=0)).ravel()
    fig, ax = plt.subplots(figsize=(7, 5))
    _draw_land(ax, model.index[floor] < 0)
    shown = ax.imshow(_layer_image(model, floor, count), origin="lower", cmap="Blues",
                      interpolation="nearest", vmin=0)
    fig.colorbar(shown, ax=ax, shrink=0.8, label="cover cells seeing the cell")
    _mark(ax, model, result.cover, marker="o", markersize=8, markerfacecolor="none",
          markeredgecolor="#08306b", label=f"cover D ({len(result.cover)})")
    _mark(ax, model, result.states, marker="o", markersize=5, color="#08306b",
          label=f"deployment C ({len(result.states)})")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.25, 1.0))
    ax.set_title(title or f"Alg. 5.3, d = {result.d:g} cells ({result.rule})", fontsize=9)
    return save_figure(fig, path)


def plot_reachability(model: DrifterCells, reach: DrifterReachability, path: Path | str,
                      title: str | None = None) -> Path:
    """The reachable set ℛ in every layer (light blue) from the release cell x_I and its
    column (green) (thesis Figs. 5.11, 5.13, 5.15)."""
    plt = pyplot()
    n = model.n_layers
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8), squeeze=False)
    for layer, ax in enumerate(axes[0]):
        _draw_land(ax, model.index[layer] < 0)
        states = model.layer_states(layer)
        ax.imshow(_layer_image(model, layer, reach.reached[states]), origin="lower",
                  cmap="Blues", vmin=-0.6, vmax=1.0, interpolation="nearest")
        here = reach.column[model.cells[reach.column, 0] == layer]
        _mark(ax, model, here, marker="o", markersize=7, color="#2ca02c")
        ax.set_title(f"layer {layer}: {int(reach.reached[states].sum())} of {len(states)} cells",
                     fontsize=9)
    fig.suptitle(title or ("Alg. 5.4 reachability" + (" (vertical moves anywhere)"
                                                      if reach.vertical_anywhere else "")),
                 fontsize=10)
    return save_figure(fig, path)


def plot_policy(model: DrifterCells, result: ValueIterationResult, path: Path | str,
                title: str | None = None) -> Path:
    """The value function and the policy of Alg. 5.5 in every layer (thesis Fig. 5.16): drift as
    a red arrow towards the cell the current carries the drifter to, up and down as blue
    triangles; the goal as a gold star."""
    plt = pyplot()
    n = model.n_layers
    fig, axes = plt.subplots(1, n, figsize=(4.4 * n, 3.9), squeeze=False)
    lo, hi = float(result.values.min()), float(result.values.max())
    for layer, ax in enumerate(axes[0]):
        _draw_land(ax, model.index[layer] < 0)
        states = model.layer_states(layer)
        shown = ax.imshow(_layer_image(model, layer, result.values[states]), origin="lower",
                          cmap="viridis", vmin=lo, vmax=hi, interpolation="nearest")
        act = result.policy[states]
        goal = np.isin(states, result.goal)
        drift = states[(act == DRIFT) & ~goal]
        src, dst = model.cells[drift], model.cells[model.mapped[drift]]
        ax.quiver(src[:, 2], src[:, 1], dst[:, 2] - src[:, 2], dst[:, 1] - src[:, 1],
                  color="#d62728", angles="xy", scale_units="xy", scale=1.6, width=0.005)
        _mark(ax, model, states[act == UP], marker="^", markersize=4, color="#1f77b4")
        _mark(ax, model, states[act == DOWN], marker="v", markersize=4, color="#1f77b4")
        _mark(ax, model, states[goal], marker="*", markersize=12, color="gold",
              markeredgecolor="black")
        ax.set_title(f"layer {layer}: drift {int((act == DRIFT).sum())}, up "
                     f"{int((act == UP).sum())}, down {int((act == DOWN).sum())}", fontsize=9)
    fig.colorbar(shown, ax=axes[0][-1], shrink=0.8, label="value")
    fig.suptitle(title or f"Alg. 5.5 policy ({result.form} form, gamma = {result.gamma:g})",
                 fontsize=10)
    return save_figure(fig, path)


def _grid_coordinates(field: FlowField, x, y) -> tuple[np.ndarray, np.ndarray]:
    """Positions in the field's coordinates as fractional columns i and rows j of its grid."""
    out = []
    for nodes, values in ((field.x, x), (field.y, y)):
        index = np.arange(len(nodes), dtype=np.float64)
        if nodes[0] > nodes[-1]:
            nodes, index = nodes[::-1], index[::-1]
        out.append(np.interp(values, nodes, index))
    return out[0], out[1]


def plot_paths(model: DrifterCells, paths: dict[str, np.ndarray], path: Path | str,
               goal=None, title: str | None = None) -> Path:
    """Drifter paths on the surface map, one panel per label: ``paths`` maps a label to the
    positions (steps + 1, drifters, 2) in the field's coordinates; start ``o``, end ``x``;
    ``goal`` states as gold stars."""
    plt = pyplot()
    items = list(paths.items())
    fig, axes = plt.subplots(1, len(items), figsize=(3.4 * len(items), 3.0), squeeze=False)
    colours = plt.get_cmap("tab10")
    for ax, (label, points) in zip(axes[0], items, strict=True):
        _draw_land(ax, model.index[0] < 0)
        if goal is not None:
            _mark(ax, model, goal, marker="*", markersize=9, color="gold",
                  markeredgecolor="black")
        for k in range(points.shape[1]):
            i, j = _grid_coordinates(model.field, points[:, k, 0], points[:, k, 1])
            ax.plot(i, j, lw=0.8, color=colours(k % 10))
            ax.plot(i[0], j[0], "o", ms=3, color=colours(k % 10))
            ax.plot(i[-1], j[-1], "x", ms=4, color=colours(k % 10))
        ax.set_title(f"{label} ({len(points) - 1} steps)", fontsize=8)
    fig.suptitle(title or "drifter paths", fontsize=9)
    return save_figure(fig, path)


def plot_coverage_curves(steps, bands: dict, path: Path | str, predicted: dict | None = None,
                         title: str | None = None) -> Path:
    """Coverage against steps: per label the mean curve with its 95% band (``bands``: label ->
    an `bounce_gym_experiments.stats.Band` over the episodes, on the points ``steps``), and the model's
    predicted coverage at the last step as a marker (``predicted``: label -> value)."""
    plt = pyplot()
    steps = np.asarray(steps)
    fig, ax = plt.subplots(figsize=(5.2, 3.4))
    colours = plt.get_cmap("tab10")
    for k, (label, band) in enumerate(bands.items()):
        ax.plot(steps, band.mean, color=colours(k), label=f"{label} (n={band.n})")
        ax.fill_between(steps, band.lo, band.hi, color=colours(k), alpha=0.2, lw=0)
        if predicted and label in predicted:
            ax.plot(steps[-1], predicted[label], marker="<", ms=7, color=colours(k),
                    linestyle="none")
    ax.set_xlabel("steps")
    ax.set_ylabel("surface cells visited (fraction)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    ax.set_title(title or "coverage: mean and 95% CI (triangles: model's prediction)",
                 fontsize=9)
    return save_figure(fig, path)
