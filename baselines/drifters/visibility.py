"""Alam 2018, thesis ch. 5, Algorithm 5.3 VISIBILITY-BASEDDEPLOYMENT: drifters with a downward
camera of range d that together see the whole seafloor (Problem 2, §5.3.2).

A drifter in water cell z of the processing layer (the surface) looks down on the seafloor layer
E_L (the deepest layer of the field) around the point below its centre, without occlusion
(Eq. 5.1). VISIBLECELLS keeps the seafloor cells seen **completely**: all four corners within d
of that point (``rule="corners"``, the default, as for the range-limited visibility of ch. 4);
``rule="centre"`` keeps the cells whose centre is within d. Distances are in cells (grid
spacings), the unit of the thesis' d = 6.

The cover 𝒟 is the greedy set cover (Chvátal 1979; Alg. 5.3 lines 4-9): repeatedly the viewing
cell that sees the most seafloor cells not yet seen, ties to the lowest state, until every
seafloor cell is seen. It is written here with sparse matrices (a few lines; no library is
needed). FINDDEPLOYMENTCELLS (line 10) then keeps, of the cover cells in one persistent group,
only the first chosen (a drifter released there visits the whole group), and keeps every
transient cover cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from baselines.drifters.behavior import PersistentBehavior
from bounce_gym import validate
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["RULES", "VisibilityDeployment", "visibility_deployment", "visible_cells"]

#: When a seafloor cell counts as visible: all four corners, or the centre, within range d.
RULES = ("corners", "centre")


@dataclass(frozen=True, eq=False)
class VisibilityDeployment:
    """The output of Alg. 5.3.

    Attributes:
        cover: (|𝒟|,) int64, the viewing cells (model states of the processing layer) in the
            order the greedy cover chose them.
        states: (|𝒞|,) int64, the deployment cells: ``cover`` without the later cells of each
            persistent group.
        seafloor: (n,) int64, the seafloor cells (model states) the cover sees.
        d: the camera range in cells.
        rule: the visibility rule.
    """

    cover: np.ndarray
    states: np.ndarray
    seafloor: np.ndarray
    d: float
    rule: str

    def __len__(self) -> int:
        return len(self.states)


def visible_cells(model: DrifterCells, d: float, layer: int = 0, seafloor: int | None = None,
                  rule: str = "corners") -> sp.csr_matrix:
    """(N_layer, N_seafloor) bool CSR: entry (z, c) iff the drifter in cell z of ``layer`` sees
    cell c of layer ``seafloor`` (default the deepest) under ``rule``; layer-local indices."""
    if not isinstance(model, DrifterCells):
        raise ConfigError(f"model: expected a DrifterCells, got {type(model).__name__}")
    d = validate.number("d", d, minimum=0.0, strict=True)
    if rule not in RULES:
        raise ConfigError(f"rule: expected one of {RULES}, got {rule!r}")
    layer = validate.integer("layer", layer, 0, model.n_layers - 1)
    floor = model.n_layers - 1 if seafloor is None else validate.integer(
        "seafloor", seafloor, 0, model.n_layers - 1)
    span = math.ceil(d)
    dj, di = np.mgrid[-span:span + 1, -span:span + 1]
    pad = 0.5 if rule == "corners" else 0.0  # the farthest corner, or the centre
    far = np.hypot(np.abs(dj) + pad, np.abs(di) + pad)
    offsets = np.column_stack((dj[far <= d], di[far <= d]))
    viewers = model.layer_states(layer)
    _, j, i = model.cells[viewers].T
    rows, cols = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
    for oj, oi in offsets:
        seen = model.state_of(floor, j + oj, i + oi)
        ok = seen >= 0
        rows.append(np.flatnonzero(ok))
        cols.append(seen[ok] - model.offsets[floor])
    n_floor = int(model.offsets[floor + 1] - model.offsets[floor])
    rows_, cols_ = np.concatenate(rows), np.concatenate(cols)
    return sp.csr_matrix((np.ones(len(rows_), dtype=bool), (rows_, cols_)),
                         shape=(len(viewers), n_floor))


def visibility_deployment(model: DrifterCells, behavior: PersistentBehavior, d: float,
                          rule: str = "corners",
                          seafloor: int | None = None) -> VisibilityDeployment:
    """Alg. 5.3 VISIBILITY-BASEDDEPLOYMENT(E_l, d, 𝓑) for the layer of ``behavior`` (the
    processing layer) looking down on layer ``seafloor`` (default: the deepest).

    Raises:
        ConfigError: bad ``d`` or ``rule``, ``behavior`` not of ``model``'s layers, or some
            seafloor cell is seen from no water cell of the processing layer (raise d).
    """
    if not isinstance(behavior, PersistentBehavior):
        raise ConfigError(f"behavior: expected a PersistentBehavior, got "
                          f"{type(behavior).__name__}")
    layer = behavior.layer
    if layer >= model.n_layers or behavior.offset != model.offsets[layer] \
            or behavior.n_cells != len(model.layer_states(layer)):
        raise ConfigError("behavior: not the analysis of a layer of this model")
    floor = model.n_layers - 1 if seafloor is None else seafloor
    seen = visible_cells(model, d, layer, floor, rule)
    n_floor = seen.shape[1]
    blind = np.flatnonzero(np.asarray(seen.sum(axis=0)).ravel() == 0)
    if len(blind):
        c = model.cells[model.offsets[floor] + blind[0]]
        raise ConfigError(f"d: {len(blind)} seafloor cells (e.g. row {c[1]}, column {c[2]}) are "
                          f"seen from no water cell of layer {layer} with d = {d} and rule "
                          f"{rule!r}; increase d")
    counts = seen.astype(np.int64)
    uncovered = np.ones(n_floor, dtype=np.int64)
    cover: list[int] = []
    while uncovered.any():  # greedy set cover, Alg. 5.3 lines 6-9
        z = int(np.argmax(counts @ uncovered))
        cover.append(z)
        uncovered[seen.indices[seen.indptr[z]:seen.indptr[z + 1]]] = 0
    kept, groups_used = [], set()
    for z in cover:  # FINDDEPLOYMENTCELLS: first cover cell of each persistent group
        g = int(behavior.group_of[z])
        if g in groups_used:
            continue
        kept.append(z)
        if g >= 0:
            groups_used.add(g)
    offset = behavior.offset
    out = [offset + np.asarray(cover, dtype=np.int64), offset + np.asarray(kept, dtype=np.int64),
           model.offsets[floor] + np.arange(n_floor)]
    for arr in out:
        arr.flags.writeable = False
    return VisibilityDeployment(cover=out[0], states=out[1], seafloor=out[2], d=float(d),
                                rule=rule)
