"""Regions of cells: goals, regions to stay in or cover, and start or deployment places.

A region is a set of water cells (layer, j, i) of the env's `DrifterCells`, given as

* ``(layer, j, i)``: one cell (j counts rows along y from the south, i columns along x);
* ``{"cell": (layer, j, i), "halo": k}``: the water cells of that layer within k cells
  (Chebyshev distance) of (j, i); ``halo`` defaults to 0;
* ``{"cells": [(layer, j, i), ...]}``: these cells;
* ``{"position": (x, y), "layer": l, "radius": r}``: the cell containing the point (x, y) (in
  the field's coordinates) and every water cell whose centre lies within r metres of it, in
  layer l (default 0) or in every layer (``"layer": "all"``); ``radius`` defaults to 0;
* ``{"layer": l}``: every water cell of layer l.

A start is drawn uniformly from its region, at the cell's centre, except a ``position`` with
radius 0, which the continuous backend starts at exactly (the cell backend at its cell). Every
bad region raises `ConfigError` naming the argument (``goal``, ``start``, ...).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from bounce_gym.cells.drifter import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import METRES_PER_DEGREE
from bounce_gym.validate import integer, number, numbers

_FORMS = ("cell", "cells", "position", "layer")


@dataclass(frozen=True)
class Region:
    """States of a region, and the exact point of a ``position`` region of radius 0."""

    states: np.ndarray  # sorted, unique, non-empty
    point: tuple[float, float] | None = None


def parse_region(spec: object, model: DrifterCells, name: str) -> Region:
    """The `Region` described by ``spec`` (module docstring) on ``model``'s cells."""
    if isinstance(spec, Sequence | np.ndarray) and not isinstance(spec, str):
        return Region(np.array([_cell(spec, model, name)]))
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{name}: expected a cell (layer, j, i) or a dict with one of "
                          f"{list(_FORMS)}, got {spec!r}")
    forms = [k for k in _FORMS if k in spec]
    form = forms[0] if forms else None
    if form == "layer" and "position" in spec:
        form = "position"
    allowed = {"cell": {"cell", "halo"}, "cells": {"cells"},
               "position": {"position", "layer", "radius"}, "layer": {"layer"}}.get(form)
    if allowed is None or set(spec) - allowed:
        extra = sorted(set(spec) - allowed) if allowed else sorted(spec)
        raise ConfigError(f"{name}: expected a dict with one of {list(_FORMS)} and their "
                          f"options (cell + halo, position + layer + radius), got keys {extra}")
    if form == "cell":
        return Region(_halo(spec["cell"], spec.get("halo", 0), model, name))
    if form == "cells":
        cells = spec["cells"]
        if isinstance(cells, str) or not isinstance(cells, Sequence | np.ndarray) \
                or not len(cells):
            raise ConfigError(f"{name}: 'cells' must be a non-empty list of (layer, j, i), "
                              f"got {cells!r}")
        return Region(np.unique([_cell(c, model, f"{name}.cells[{k}]")
                                 for k, c in enumerate(cells)]))
    if form == "layer":
        layer = integer(f"{name}.layer", spec["layer"], 0, model.n_layers - 1)
        return Region(model.layer_states(layer))
    return _around(spec, model, name)


def _cell(value: object, model: DrifterCells, name: str) -> int:
    if isinstance(value, str) or not isinstance(value, Sequence | np.ndarray) or len(value) != 3:
        raise ConfigError(f"{name}: expected a cell (layer, j, i), got {value!r}")
    n_layers, ny, nx = model.index.shape
    layer, j, i = (integer(f"{name}[{k}]", v, 0, top - 1)
                   for k, (v, top) in enumerate(zip(value, (n_layers, ny, nx), strict=True)))
    state = int(model.index[layer, j, i])
    if state < 0:
        raise ConfigError(f"{name}: cell {(layer, j, i)} is land")
    return state


def _halo(cell: object, halo: object, model: DrifterCells, name: str) -> np.ndarray:
    if isinstance(cell, str) or not isinstance(cell, Sequence | np.ndarray) or len(cell) != 3:
        raise ConfigError(f"{name}.cell: expected (layer, j, i), got {cell!r}")
    n_layers, ny, nx = model.index.shape
    layer, j, i = (integer(f"{name}.cell[{k}]", v, 0, top - 1)
                   for k, (v, top) in enumerate(zip(cell, (n_layers, ny, nx), strict=True)))
    k = integer(f"{name}.halo", halo, 0)
    block = model.index[layer, max(j - k, 0):j + k + 1, max(i - k, 0):i + k + 1]
    states = np.sort(block[block >= 0])
    if not len(states):
        raise ConfigError(f"{name}: no water cell within {k} cells of {(layer, j, i)}")
    return states


def _around(spec: Mapping, model: DrifterCells, name: str) -> Region:
    field = model.field
    point = numbers(f"{name}.position", spec["position"])
    if point.shape != (2,):
        raise ConfigError(f"{name}.position: expected (x, y), got {spec['position']!r}")
    x, y = float(point[0]), float(point[1])
    radius = number(f"{name}.radius", spec.get("radius", 0.0), minimum=0.0)
    layer = spec.get("layer", 0)
    if layer == "all":
        layers = np.arange(model.n_layers)
    else:
        layers = np.array([integer(f"{name}.layer", layer, 0, model.n_layers - 1)])
    j, i, inside = field.nearest_node(x, y)
    if not inside:
        raise ConfigError(f"{name}.position: ({x:g}, {y:g}) lies outside the grid of the flow "
                          f"{field.name!r} (x in [{field.x[0]:g}, {field.x[-1]:g}], y in "
                          f"[{field.y[0]:g}, {field.y[-1]:g}] at the nodes)")
    own = model.index[layers, int(j), int(i)]
    cx, cy = model.centre(np.arange(model.n_states))
    near = np.isin(model.cells[:, 0], layers) & (_metres(field, cx - x, cy - y, y) <= radius)
    states = np.union1d(own[own >= 0], np.flatnonzero(near))
    if not len(states):
        raise ConfigError(f"{name}: no water cell at or within {radius:g} m of ({x:g}, {y:g}) "
                          f"in layer {layer}")
    exact = radius == 0 and len(layers) == 1 and own[0] >= 0
    return Region(states.astype(np.int64), (x, y) if exact else None)


def _metres(field, dx, dy, y) -> np.ndarray:
    """Length in metres of the coordinate offsets (dx, dy) near latitude/northing ``y``."""
    if field.crs == "lonlat":
        return np.hypot(dx * METRES_PER_DEGREE * np.cos(np.radians(y)), dy * METRES_PER_DEGREE)
    return np.hypot(dx, dy)


def distance_to(field, x: np.ndarray, y: np.ndarray, cx: np.ndarray, cy: np.ndarray
                ) -> np.ndarray:
    """(N,) horizontal distance in metres from each point (x[n], y[n]) to the nearest of the
    points (cx, cy)."""
    return _metres(field, cx[None, :] - x[:, None], cy[None, :] - y[:, None],
                   y[:, None]).min(axis=1)
