"""Alam 2018, thesis ch. 5, Algorithm 5.1 PERSISTENTBEHAVIOR: the long-term behaviour of the
water flow in one layer, as plain data.

The analysis itself is the shared Markov layer's (`bounce_gym.markov.gcm.layer_gcm` on the
layer's drift chain of `bounce_gym.cells.DrifterCells`): persistent groups are the **closed**
communicating classes (the sinks of the condensation; the printed test "every vertex of the
component communicates with all others" holds for every strongly connected component,
docs/choices/drifters.md "Persistent groups of a drifter layer are closed classes"); transient cells are
grouped by their set of domiciles (Def. 5.4.2: single-domicile groups B(g), multiple-domicile
groups B(g, h, ...)); the expected absorption times are a = (I - Q)^-1 1 (Thm 5.4.3, Eq. 5.7).
The thesis' connectivity matrix C (the transitive closure of the layer's graph) is not formed:
`PersistentBehavior.reach` answers "which cells does this cell lead to" by a breadth-first search.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from baselines.drifters.graph import reachable
from bounce_gym import validate
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.markov.gcm import layer_gcm

__all__ = ["PersistentBehavior", "persistent_behavior"]


@dataclass(frozen=True, eq=False)
class PersistentBehavior:
    """The output of Alg. 5.1 for one layer. Cells are **model states** (the numbering of
    `DrifterCells`: the layer's states are ``offset .. offset + n_cells - 1``); per-cell arrays
    are indexed by ``state - offset``.

    Attributes:
        layer: the layer analysed (0 = surface).
        offset: the first state of the layer.
        graph: (n_cells, n_cells) CSR, the layer's one-step drift probabilities on layer-local
            indices (row-stochastic).
        groups: the persistent groups 𝓑, each a sorted array of states; group g is numbered by
            its smallest state.
        transient_groups: the transient groups 𝓣, ``{frozenset of groups: sorted states}``:
            key ``{g}`` is the domain of attraction B(g), a larger key a boundary region
            B(g, h, ...); ordered by key size, then by the sorted key.
        group_of: (n_cells,) int64, the persistent group of each cell, -1 if transient.
        transient_group_of: (n_cells,) int64, the position of each cell's transient group in
            ``transient_groups``, -1 if persistent.
        absorption_time: (n_cells,) expected steps until a persistent group is entered
            (thesis Eq. 5.7); 0 on persistent cells.
        absorption: (n_cells, n_groups) probability of ending in each group; one-hot on
            persistent cells. Not in the thesis (docs/choices/drifters.md).
    """

    layer: int
    offset: int
    graph: sp.csr_matrix
    groups: tuple[np.ndarray, ...]
    transient_groups: dict[frozenset[int], np.ndarray]
    group_of: np.ndarray
    transient_group_of: np.ndarray
    absorption_time: np.ndarray
    absorption: np.ndarray

    @property
    def n_cells(self) -> int:
        return self.graph.shape[0]

    @property
    def states(self) -> np.ndarray:
        """(n_cells,) the layer's states."""
        return self.offset + np.arange(self.n_cells)

    @property
    def persistent(self) -> np.ndarray:
        """(n_cells,) bool, persistent cells (the set 𝓛 of Alg. 5.1 line 12)."""
        return self.group_of >= 0

    def reach(self, states) -> np.ndarray:
        """(n_cells,) bool: the cells of the layer that any of ``states`` leads to, the states
        included (the rows of the thesis' connectivity matrix C, or'ed)."""
        local = self.local(states)
        return reachable(self.graph, local)

    def local(self, states, field: str = "states") -> np.ndarray:
        """Layer-local indices (state - offset) of ``states`` of this layer; `ConfigError` naming
        ``field`` for anything else."""
        states = np.asarray(states)
        if states.size == 0:
            return np.zeros(0, dtype=np.int64)
        if states.dtype.kind not in "iu":
            raise ConfigError(f"{field}: expected integer states of layer {self.layer}")
        local = states.astype(np.int64).ravel() - self.offset
        if np.any((local < 0) | (local >= self.n_cells)):
            raise ConfigError(f"{field}: expected states of layer {self.layer} in "
                              f"[{self.offset}, {self.offset + self.n_cells - 1}]")
        return local


def persistent_behavior(model: DrifterCells, layer: int = 0) -> PersistentBehavior:
    """Alg. 5.1 PERSISTENTBEHAVIOR(E_l, F_l) on layer ``layer`` of ``model`` (the flow snapshot
    and ρ of the model): persistent groups, transient groups by domicile set, absorption times
    and probabilities.

    Raises:
        ConfigError: ``model`` is not a `DrifterCells`, or ``layer`` is not one of its layers.
    """
    if not isinstance(model, DrifterCells):
        raise ConfigError(f"model: expected a DrifterCells, got {type(model).__name__}")
    layer = validate.integer("layer", layer, 0, model.n_layers - 1)
    offset = int(model.offsets[layer])
    res = layer_gcm(model, layer)
    n = res.n_cells
    groups = tuple(offset + g for g in res.groups)
    transient_groups = {key: offset + cells for key, cells in res.domicile_groups().items()}
    transient_group_of = np.full(n, -1, dtype=np.int64)
    for k, cells in enumerate(transient_groups.values()):
        transient_group_of[cells - offset] = k
    absorption_time = np.zeros(n)
    absorption = np.zeros((n, res.n_groups))
    if len(res.transient):
        absorption_time[res.transient] = res.absorption_time
        absorption[res.transient] = res.absorption
    pers = np.flatnonzero(res.persistent)
    absorption[pers, res.group_of[pers]] = 1.0
    for arr in (transient_group_of, absorption_time, absorption, *groups,
                *transient_groups.values()):
        arr.flags.writeable = False
    group_of = res.group_of.astype(np.int64)
    group_of.flags.writeable = False
    return PersistentBehavior(layer=layer, offset=offset, graph=res.P, groups=groups,
                              transient_groups=transient_groups, group_of=group_of,
                              transient_group_of=transient_group_of,
                              absorption_time=absorption_time, absorption=absorption)
