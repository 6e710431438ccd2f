"""The discrete drifter model of Alam 2018 (thesis ch. 5, §5.3.1 and §5.4.2-5.4.3): water cells
per layer, the flow's unit-step cell map with perfect-motion probability ρ, and the 3-D actions of a
profiling drifter.

**States.** Every water cell of every layer of a `FlowField` snapshot, numbered layer-major
(layer 0 = surface first), then row-major from the south-west: ``state = offsets[layer] + k``
where k counts the water cells of the layer in (j, i) order, j along y (north), i along x (east).
``cells[state] = (layer, j, i)``; ``index[layer, j, i]`` is the inverse (-1 on land).

**Drift** (thesis Eq. 5.3 and §5.4.3, with the choices of docs/choices/drifters.md, "Drifter cell map: one
cell per step", "The uncertainty set is the target's neighbourhood" and "Drifter boundary
cells"):

* the mapped cell z' of a cell z is one unit step from its centre along the local flow
  direction, measured in cells (heading ``atan2(v/dy, u/dx)`` with the metric spacing dx, dy): a
  king move to one of the 8 neighbours with the tie rule of `king_offset`. This is the Euler step
  of Eq. 5.3 with Δt = cell size / |F| per cell. (``step="flowline"`` follows the flow line
  for the same Δt instead.) A cell with zero velocity, or whose step ends on land or off the
  grid, maps to itself;
* a **boundary cell** (one with a land or off-grid 8-neighbour) moves uniformly to {z} ∪ its
  water 8-neighbours (§5.3.1);
* any other cell moves to z' with probability ρ and to each water 8-neighbour of z' with
  probability (1 - ρ) / (|A(z)| - 1), where A(z) = {z'} ∪ water 8-neighbours of z' (§5.4.3; the
  printed "|A(i)| - 1|" read as |A(i)| - 1).

The drift matrix is row-stochastic (``P[z, z'] = Pr(z -> z')``) and block-diagonal by layer.

**Actions** of a profiling drifter (thesis §5.3.2, U = {-1 up, +1 down, 0 drift}) are encoded
as `Discrete(3)`: ``DRIFT = 0`` (the layer's drift row), ``UP = 1`` (the same (j, i) one layer
shallower), ``DOWN = 2`` (one layer deeper). A vertical move is deterministic and legal only if
that layer exists and the cell is water there (`legal`); the rows of an illegal action are zero
in `action_matrices`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from bounce_gym import validate
from bounce_gym.cells.model import king_offset
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.flows import FlowField
from bounce_gym.flows.integrate import rk4_step

__all__ = ["ACTIONS", "DOWN", "DRIFT", "FLOWLINE_SUBSTEPS", "STEPS", "UP", "DrifterCells"]

#: Cell maps: the thesis' Euler unit step (Eq. 5.3), or the flow line over the same time.
STEPS = ("euler", "flowline")
#: RK4 substeps of one ``"flowline"`` cell step.
FLOWLINE_SUBSTEPS = 4

DRIFT, UP, DOWN = 0, 1, 2
#: Action names by code.
ACTIONS = ("drift", "up", "down")
_NEIGHBOURS = tuple((dj, di) for dj in (-1, 0, 1) for di in (-1, 0, 1) if dj or di)


class DrifterCells:
    """The cell model of one snapshot of a flow field (see the module docstring).

    Args:
        field: the flow.
        rho: perfect-motion probability ρ in (0, 1] (docs/choices/drifters.md, "Perfect-motion
            probability ρ = 0.8").
        t: time of the snapshot in seconds (linear between the field's snapshots); None for a
            static field.
        outside: ``"error"`` or ``"hold"``, for ``t`` outside the field's time range.
        step: the cell map: ``"euler"`` (default, thesis Eq. 5.3: one cell along the local flow
            direction) or ``"flowline"`` (the end of the snapshot's flow line after the same
            time Δt = cell size / |F|, integrated with RK4, nearest node clamped to the
            3 x 3 neighbourhood; docs/choices/drifters.md, "Drifter cell map: one cell per step").

    Attributes:
        field, rho, t, step: as given.
        index: (L, Ny, Nx) int64, the state of each cell, -1 on land.
        cells: (N, 3) int64, (layer, j, i) of each state.
        offsets: (L + 1,) int64, the states of layer k are ``offsets[k]:offsets[k + 1]``.
        mapped: (N,) int64, the state z' of the unit-step map (the perfect motion).
        boundary: (N,) bool, boundary cells.
        legal: (N, 3) bool, the legal actions of each state (drift always).
        vertical: (N, 3) int64, the state an action leads to for UP and DOWN (-1 if illegal);
            column DRIFT is -1 (drift is random).
    """

    def __init__(self, field: FlowField, rho: float = 0.8, t: float | None = None,
                 outside: str = "error", step: str = "euler") -> None:
        if not isinstance(field, FlowField):
            raise ConfigError(f"field: expected a FlowField, got {type(field).__name__}")
        if step not in STEPS:
            raise ConfigError(f"step: expected one of {STEPS}, got {step!r}")
        rho = validate.number("rho", rho, minimum=0.0, strict=True)
        if rho > 1:
            raise ConfigError(f"rho: expected a probability in (0, 1], got {rho!r}")
        self.field, self.rho, self.t, self.step = field, rho, t, step
        u, v = field.snapshot(t, outside)
        water = field.water
        n_layers, ny, nx = water.shape
        self.index = np.full(water.shape, -1, dtype=np.int64)
        self.index[water] = np.arange(int(water.sum()))
        self.cells = np.argwhere(water).astype(np.int64)
        self.offsets = np.concatenate(([0], np.cumsum(water.reshape(n_layers, -1).sum(axis=1))))
        lay, j, i = self.cells.T
        dx, dy = field.metric_spacing()
        cu, cv = u[lay, j, i] / dx[j, i], v[lay, j, i] / dy[j, i]  # cells per second
        still = (cu == 0) & (cv == 0)
        if step == "euler":  # one cell along the flow: a king move
            di, dj = king_offset(np.arctan2(cv, cu))
        else:  # follow the snapshot's flow line for the time to cross one cell
            di, dj = self._flowline_offsets(lay, j, i, np.hypot(cu, cv), still)
        tj, ti = j + np.where(still, 0, dj), i + np.where(still, 0, di)
        target = self._state_at(lay, tj, ti)
        self.mapped = np.where(target >= 0, target, np.arange(len(lay)))
        n_water = self._water_neighbours(lay, j, i)
        self.boundary = n_water < 8
        # vertical moves
        self.vertical = np.full((len(lay), 3), -1, dtype=np.int64)
        self.vertical[:, UP] = self._state_at(lay - 1, j, i)
        self.vertical[:, DOWN] = self._state_at(lay + 1, j, i)
        self.legal = self.vertical >= 0
        self.legal[:, DRIFT] = True
        for arr in (self.index, self.cells, self.offsets, self.mapped, self.boundary,
                    self.vertical, self.legal):
            arr.flags.writeable = False
        self._drift: sp.csr_matrix | None = None
        self._drift_cumsum: np.ndarray | None = None  # running sum of the drift matrix's entries

    # -- sizes and lookups ------------------------------------------------------------------
    @property
    def n_states(self) -> int:
        return len(self.cells)

    @property
    def n_layers(self) -> int:
        return self.index.shape[0]

    def layer_states(self, layer: int) -> np.ndarray:
        """The states of layer ``layer``, in order."""
        layer = validate.integer("layer", layer, 0, self.n_layers - 1)
        return np.arange(self.offsets[layer], self.offsets[layer + 1])

    def state_of(self, layer, j, i) -> np.ndarray:
        """States of cells (layer, j, i) (arrays broadcast); -1 for land or off-grid cells."""
        return self._state_at(*np.broadcast_arrays(np.asarray(layer), np.asarray(j),
                                                   np.asarray(i)))

    def state_at_point(self, x, y, layer) -> np.ndarray:
        """States of the cells containing points (x, y) in ``layer``; -1 on land or outside."""
        j, i, inside = self.field.nearest_node(x, y)
        layer = np.broadcast_to(np.asarray(layer), j.shape)
        return np.where(inside, self._state_at(layer, j, i), -1)

    def centre(self, states) -> tuple[np.ndarray, np.ndarray]:
        """(x, y) of the cell centres of ``states``."""
        cells = self.cells[np.asarray(states)]
        return self.field.node_xy(cells[..., 1], cells[..., 2])

    # -- transition matrices ----------------------------------------------------------------
    def drift_matrix(self) -> sp.csr_matrix:
        """(N, N) row-stochastic CSR, the drift (GCM) transitions of every layer."""
        if self._drift is None:
            self._drift = self._build_drift()
        return self._drift

    def transition_matrix(self, layer: int) -> sp.csr_matrix:
        """(N_l, N_l) row-stochastic CSR of layer ``layer`` on its own states (state
        ``offsets[layer] + k`` is row k)."""
        s = self.layer_states(layer)
        lo, hi = (s[0], s[-1] + 1) if len(s) else (0, 0)
        return self.drift_matrix()[lo:hi, lo:hi].tocsr()

    def action_matrices(self) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
        """(drift, up, down), each (N, N) CSR; rows of illegal vertical actions are zero."""
        n = self.n_states
        out = [self.drift_matrix()]
        for a in (UP, DOWN):
            rows = np.flatnonzero(self.legal[:, a])
            out.append(sp.csr_matrix((np.ones(len(rows)), (rows, self.vertical[rows, a])),
                                     shape=(n, n)))
        return out[0], out[1], out[2]

    def sample(self, states, actions, rng: np.random.Generator) -> np.ndarray:
        """Next states of ``states`` under ``actions`` (arrays of equal shape), drawn from
        ``rng``. Raises `ActionError` for an unknown or illegal action."""
        states = np.asarray(states, dtype=np.int64)
        actions = np.asarray(actions)
        if actions.shape != states.shape or actions.dtype.kind not in "iu":
            raise ActionError(f"actions: expected integers of shape {states.shape}")
        if np.any((actions < 0) | (actions > 2)):
            raise ActionError(f"actions: expected codes 0 (drift), 1 (up), 2 (down), got "
                              f"{np.unique(actions).tolist()}")
        if np.any((states < 0) | (states >= self.n_states)):
            raise ActionError(f"states: expected states in [0, {self.n_states - 1}]")
        bad = ~self.legal[states, actions]
        if bad.any():
            k = int(np.flatnonzero(bad.ravel())[0])
            raise ActionError(f"actions: {ACTIONS[int(actions.ravel()[k])]} is illegal in "
                              f"state {int(states.ravel()[k])} (cell "
                              f"{tuple(self.cells[states.ravel()[k]].tolist())})")
        drift = actions == DRIFT
        out = np.empty(states.shape, dtype=np.int64)
        out[~drift] = self.vertical[states[~drift], actions[~drift]]
        out[drift] = _sample_rows(self.drift_matrix(), self._cumsum(), states[drift], rng)
        return out

    def sample_one(self, state: int, action: int, rng: np.random.Generator) -> int:
        """`sample` of one state and action, in plain ints: the same draw from ``rng`` (one
        uniform number for a drift, none for a vertical move) and the same next state, without
        array overheads (the hot path of a single-drifter environment)."""
        if not (0 <= state < self.n_states and action in (DRIFT, UP, DOWN)):
            raise ActionError(f"state {state}, action {action}: expected a state in "
                              f"[0, {self.n_states - 1}] and an action 0, 1 or 2")
        if not self.legal[state, action]:
            raise ActionError(f"actions: {ACTIONS[action]} is illegal in state {state} (cell "
                              f"{tuple(self.cells[state].tolist())})")
        if action != DRIFT:
            return int(self.vertical[state, action])
        P, cum = self.drift_matrix(), self._cumsum()
        start, stop = int(P.indptr[state]), int(P.indptr[state + 1])
        before = float(cum[start - 1]) if start > 0 else 0.0
        k = int(np.searchsorted(cum, before + rng.random(), side="right"))
        return int(P.indices[min(max(k, start), stop - 1)])

    def _cumsum(self) -> np.ndarray:
        """Running sum of the drift matrix's entries (`_sample_rows`), computed once."""
        if self._drift_cumsum is None:
            self._drift_cumsum = np.cumsum(self.drift_matrix().data)
        return self._drift_cumsum

    # -- internals --------------------------------------------------------------------------
    def _flowline_offsets(self, lay, j, i, speed, still) -> tuple[np.ndarray, np.ndarray]:
        """Grid offsets (di, dj) to the node nearest the end of the flow line that starts at each
        cell centre and runs for one cell's crossing time 1 / speed (RK4, `FLOWLINE_SUBSTEPS`
        substeps, time frozen at the snapshot), clamped to the 3 x 3 neighbourhood."""
        x, y = self.field.node_xy(j, i)
        dt = np.where(still, 0.0, 1.0 / np.where(still, 1.0, speed)) / FLOWLINE_SUBSTEPS
        for _ in range(FLOWLINE_SUBSTEPS):
            x, y = rk4_step(self.field, x, y, lay, dt, self.t, frozen=True, outside="hold")
        tj, ti, _ = self.field.nearest_node(x, y)
        return np.clip(ti - i, -1, 1), np.clip(tj - j, -1, 1)

    def _state_at(self, layer, j, i) -> np.ndarray:
        n_layers, ny, nx = self.index.shape
        ok = (layer >= 0) & (layer < n_layers) & (j >= 0) & (j < ny) & (i >= 0) & (i < nx)
        out = np.full(np.shape(ok), -1, dtype=np.int64)
        out[ok] = self.index[layer[ok], j[ok], i[ok]]
        return out

    def _water_neighbours(self, lay, j, i) -> np.ndarray:
        count = np.zeros(len(lay), dtype=np.int64)
        for dj, di in _NEIGHBOURS:
            count += self._state_at(lay, j + dj, i + di) >= 0
        return count

    def _build_drift(self) -> sp.csr_matrix:
        n = self.n_states
        lay, j, i = self.cells.T
        z = np.arange(n)
        rows, cols, vals = [], [], []
        # boundary cells: uniform over {z} and the water neighbours
        b = np.flatnonzero(self.boundary)
        p_b = 1.0 / (1 + self._water_neighbours(lay[b], j[b], i[b]))
        rows.append(b)
        cols.append(b)
        vals.append(p_b)
        for dj, di in _NEIGHBOURS:
            s = self._state_at(lay[b], j[b] + dj, i[b] + di)
            ok = s >= 0
            rows.append(b[ok])
            cols.append(s[ok])
            vals.append(p_b[ok])
        # other cells: rho to z', (1 - rho) / k to each water neighbour of z'
        f = z[~self.boundary]
        tgt = self.mapped[f]
        tl, tj, ti = self.cells[tgt].T
        k = self._water_neighbours(tl, tj, ti)  # >= 1: z itself is a neighbour of z' != z
        rows.append(f)
        cols.append(tgt)
        vals.append(np.full(len(f), self.rho))
        for dj, di in _NEIGHBOURS:
            s = self._state_at(tl, tj + dj, ti + di)
            ok = s >= 0
            rows.append(f[ok])
            cols.append(s[ok])
            vals.append((1.0 - self.rho) / k[ok])
        P = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(n, n))
        P.eliminate_zeros()
        return P


def _sample_rows(P: sp.csr_matrix, cum: np.ndarray, rows: np.ndarray,
                 rng: np.random.Generator) -> np.ndarray:
    """One column per row index, drawn with the row's probabilities (rows sum to 1); ``cum`` is
    ``np.cumsum(P.data)``, computed once per matrix rather than per call."""
    if len(rows) == 0:
        return np.zeros(0, dtype=np.int64)
    start = P.indptr[rows]
    stop = P.indptr[rows + 1]
    before = np.where(start > 0, cum[np.maximum(start - 1, 0)], 0.0)
    k = np.searchsorted(cum, before + rng.random(len(rows)), side="right")
    k = np.clip(k, start, stop - 1)
    return P.indices[k].astype(np.int64)
