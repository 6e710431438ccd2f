"""Alam 2018, thesis ch. 5, Algorithm 5.2 DEPLOYMENTLOCATIONS: where to release drifters so
that, together, they visit every cell of a layer (Problem 1, §5.3.2).

One cell is drawn at random (seeded) from each persistent group (Alg. 5.2 line 3): a drifter
released there visits every cell of its group with probability 1. MINCELLSINTRANSIENTGROUP
(line 5) is only described as "descending absorption times and the most connected cells"; we take
one cell from each **source strongly connected component** of the subgraph induced on each
transient group (docs/choices/drifters.md, "Alg. 5.2: one cell per source component"): the cell with the
largest expected absorption time (Eq. 5.7), ties to the lowest state. (The second key of the
thesis, the number of cells reached, is the same for every cell of one component.)

The result is minimal for **group-wise coverage**: every cell is reached from a deployment cell
of its own group (persistent group or transient group), and no smaller set achieves that
(`group_coverage`). Paths between two cells of one transient group never leave it (a domicile
set cannot grow along a path), so a source component can be entered only from itself.
Coverage by plain reachability ("some deployment cell leads to it") is weaker: in the
``two_sink`` field a single cell leads to all 522 cells.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from baselines.drifters.behavior import PersistentBehavior
from baselines.drifters.graph import reachable, source_components
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["Deployment", "deploy_cells", "deployment_locations", "group_coverage"]


@dataclass(frozen=True, eq=False)
class Deployment:
    """Deployment cells of one layer.

    Attributes:
        states: (k,) int64, the model states to release the drifters in, in the order chosen.
        method: the algorithm that chose them.
    """

    states: np.ndarray
    method: str

    def __len__(self) -> int:
        return len(self.states)


#: relative tolerance within which two absorption times count as equal (Alg. 5.2's argmax)
TIE_RTOL = 1e-9


def deployment_locations(behavior: PersistentBehavior, seed: int = 0) -> Deployment:
    """Alg. 5.2 DEPLOYMENTLOCATIONS(𝓑, 𝓣, C, a): one seeded random cell per persistent group,
    then for every transient group one cell per source component (module docstring). ``|C|`` is
    the number of drifters."""
    _check_behavior(behavior)
    rng = np.random.default_rng(seed)
    chosen = [int(rng.choice(group)) for group in behavior.groups]
    for cells in behavior.transient_groups.values():
        local = cells - behavior.offset
        for comp in source_components(behavior.graph, local):
            times = behavior.absorption_time[comp]
            # the longest absorption time; cells whose times agree to rounding (symmetric
            # flows give exact ties that the solver's last bits decide) go to the lowest index
            near = np.flatnonzero(times >= times.max() * (1.0 - TIE_RTOL))
            chosen.append(behavior.offset + int(comp[near[np.argmin(comp[near])]]))
    return _deployment(chosen, "Alg. 5.2")


def group_coverage(behavior: PersistentBehavior, states) -> np.ndarray:
    """(n_cells,) bool: the cells of the layer reached from a cell of ``states`` that lies in
    the same persistent or transient group (the coverage Alg. 5.2 guarantees)."""
    _check_behavior(behavior)
    local = behavior.local(states)
    covered = np.zeros(behavior.n_cells, dtype=bool)
    members = [g - behavior.offset for g in behavior.groups]
    members += [t - behavior.offset for t in behavior.transient_groups.values()]
    for cells in members:
        mask = np.zeros(behavior.n_cells, dtype=bool)
        mask[cells] = True
        starts = local[mask[local]]
        if len(starts):
            covered |= reachable(behavior.graph, starts) & mask
    return covered


def deploy_cells(model: DrifterCells, states) -> list[tuple[int, int, int]]:
    """The cells (layer, j, i) of ``states``: one region per drifter, the ``deploy`` argument of
    ``bounce_gym/MultiDrifter-v0``."""
    states = np.asarray(states, dtype=np.int64)
    return [(int(lay), int(j), int(i)) for lay, j, i in model.cells[states]]


def _check_behavior(behavior) -> None:
    if not isinstance(behavior, PersistentBehavior):
        raise ConfigError(f"behavior: expected a PersistentBehavior (persistent_behavior(...)), "
                          f"got {type(behavior).__name__}")


def _deployment(states, method: str) -> Deployment:
    states = np.asarray(states, dtype=np.int64)
    states.flags.writeable = False
    return Deployment(states=states, method=method)
