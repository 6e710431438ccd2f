"""A drifter cell model whose drift is measured rather than postulated: generalized cell mapping
by sampling (Hsu 1980; Hsu, *Cell-to-Cell Mapping*, 1987, ch. 10-11).

The thesis' model (`DrifterCells`) moves a drifter one cell per decision along the local flow
with perfect-motion probability ρ. `SampledDrifterCells` keeps its states, cells and vertical
moves but replaces the drift by matrices estimated from a simulator: ``P_k[z, z']`` is the
fraction of the sample points of cell z that end one decision step later in cell z'
(`bounce_gym.envs.drifters.sampled` builds them with the env's own dynamics). The drift may
depend on the decision step k: ``drifts[k]`` is the step k, and the last matrix holds for every
later step (after a time-dependent field's last snapshot the currents are held, so the steps
from then on are alike).

``vertical_then_drift``: in the continuous env an up or down move changes the layer instantly
and the drifter then drifts for the rest of the step in its new layer, so the action matrix of
up is ``U P_k`` (U the deterministic move of `DrifterCells`); on the cell backend a vertical
move is the whole step (``U``). `sample` draws from the last (held) step's matrices.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from bounce_gym.cells.drifter import DRIFT, DrifterCells
from bounce_gym.errors import ActionError, ConfigError

__all__ = ["SampledDrifterCells"]

#: Largest deviation of a row sum from 1 a sampled drift may have.
_ROW_TOL = 1e-9


class SampledDrifterCells(DrifterCells):
    """The states of ``base`` with sampled drift matrices (module docstring).

    Args:
        base: the exact model whose states, cells and vertical moves are kept (its ``rho``,
            ``mapped`` and ``boundary`` describe that model, not the sampled drift).
        drifts: one (N, N) row-stochastic matrix per decision step, the last one holding for
            every later step; entries only within a layer.
        vertical_then_drift: whether an up/down move is followed by the step's drift (module
            docstring).
        samples: sample points per cell the matrices were estimated from.
        seed: the seed of the sample points (and of the diffusion).
        doubling_tv: the convergence check: the mean over cells and steps of the total-variation
            distance between the rows estimated from the first half of the samples and from all
            of them (``max_doubling_tv``: the largest row's).

    Raises:
        ConfigError: a matrix of the wrong shape, not row-stochastic, or crossing layers.
    """

    def __init__(self, base: DrifterCells, drifts: Sequence[sp.spmatrix], *,
                 vertical_then_drift: bool, samples: int, seed: int, doubling_tv: float,
                 max_doubling_tv: float) -> None:
        super().__init__(base.field, base.rho, t=base.t, outside="hold", step=base.step)
        if not len(drifts):
            raise ConfigError("drifts: expected at least one drift matrix")
        self.drifts = tuple(self._checked(k, P) for k, P in enumerate(drifts))
        self.vertical_then_drift = bool(vertical_then_drift)
        self.samples, self.seed = samples, seed
        self.doubling_tv, self.max_doubling_tv = doubling_tv, max_doubling_tv
        self._drift = self.drifts[-1]
        self._actions: dict[int, tuple[sp.csr_matrix, ...]] = {}

    @property
    def n_steps(self) -> int:
        """Decision steps with a matrix of their own (the last one holds from then on)."""
        return len(self.drifts)

    def drift_at(self, step: int) -> sp.csr_matrix:
        """The drift matrix of decision step ``step`` (0 = the first step of an episode)."""
        return self.drifts[min(max(int(step), 0), self.n_steps - 1)]

    def action_matrices(self, step: int | None = None
                        ) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
        """(drift, up, down) of decision step ``step`` (None: the held last step), each (N, N)
        CSR; rows of illegal vertical moves are zero."""
        k = self.n_steps - 1 if step is None else min(max(int(step), 0), self.n_steps - 1)
        if k not in self._actions:
            drift = self.drifts[k]
            up, down = (self._vertical(a) for a in (1, 2))
            if self.vertical_then_drift:
                up, down = (up @ drift).tocsr(), (down @ drift).tocsr()
            self._actions[k] = (drift, up, down)
        return self._actions[k]

    def sample(self, states, actions, rng: np.random.Generator) -> np.ndarray:
        """Next states under the held last step's matrices (a vertical move is followed by a
        drift where ``vertical_then_drift``). Raises `ActionError` as `DrifterCells.sample`."""
        out = super().sample(states, actions, rng)
        if not self.vertical_then_drift:
            return out
        moved = np.asarray(actions) != DRIFT
        out[moved] = super().sample(out[moved], np.zeros(int(moved.sum()), dtype=np.int64),
                                    rng)
        return out

    def sample_one(self, state: int, action: int, rng: np.random.Generator) -> int:
        """`sample` of one state and action."""
        if action not in (0, 1, 2):
            raise ActionError(f"action {action}: expected 0, 1 or 2")
        return int(self.sample(np.array([state]), np.array([action]), rng)[0])

    # -- internals --------------------------------------------------------------------------
    def _vertical(self, action: int) -> sp.csr_matrix:
        rows = np.flatnonzero(self.legal[:, action])
        n = self.n_states
        return sp.csr_matrix((np.ones(len(rows)), (rows, self.vertical[rows, action])),
                             shape=(n, n))

    def _checked(self, k: int, P: sp.spmatrix) -> sp.csr_matrix:
        n = self.n_states
        P = sp.csr_matrix(P, dtype=np.float64)
        if P.shape != (n, n):
            raise ConfigError(f"drifts[{k}]: expected shape ({n}, {n}), got {P.shape}")
        P.sum_duplicates()
        P.eliminate_zeros()
        if not np.all(np.isfinite(P.data)) or np.any(P.data < 0):
            raise ConfigError(f"drifts[{k}]: entries must be finite and >= 0")
        rows = np.asarray(P.sum(axis=1)).ravel()
        if np.any(np.abs(rows - 1.0) > _ROW_TOL):
            raise ConfigError(f"drifts[{k}]: rows must sum to 1")
        coo = P.tocoo()
        if np.any(self.cells[coo.row, 0] != self.cells[coo.col, 0]):
            raise ConfigError(f"drifts[{k}]: a drift moves within its layer only")
        P.data.flags.writeable = False
        return P
