"""A histogram (discrete Bayes) filter over the decision states of a sampled cell mapping.

The robot senses only its bumps and its clock. Between two bumps it commands one bounce angle
(index ``a`` of Φ) and reads the ticks its drive took; a generalized cell mapping
(`bounce_gym.cells.outcomes.BumpOutcomes`) gives the outcome table P(z', t | z, a). The belief
b(z) over decision states is updated at every bump by Bayes' rule on that table (Thrun, Burgard &
Fox, *Probabilistic Robotics*, 2005, sec. 2.4 and 4.1, the discrete Bayes filter):

    b'(z') ∝ Σ_z b̄(z) L_t(z, z'),    b̄ = (1 − ρ) b + ρ b₀,

with the observation likelihood

    L_t(z, z') = (1 − η) P(z', t | z, a) + η · (1 / (2τ + 1)) Σ_{|d| ≤ τ} P(z', t + d | z, a).

**Why the two mixings.** The table is estimated from finitely many sample poses and lumps all
poses of a cell and heading bin into one state, so a tick count the robot really reads may have
no sample behind it (a drive length on a tick boundary), and the state sequence is only
approximately Markov. Pure Bayes on the table would then drop the true state for good and could
concentrate on a wrong one. The tick-tolerant term (weight η, τ ticks each side) keeps every
state whose samples read within τ ticks of the clock; the restart term ρ (the robot may, with
probability ρ, be anywhere the prior b₀ says — the "kidnapped robot" hedge of Thrun et al.,
sec. 8.3.3) keeps every state reachable so that later bumps can correct an early mistake. Both
are an exact Bayes filter on a slightly broader model, so a belief never claims more than that
model supports; with η = ρ = 0 it is exact Bayes on the table.

**An observation the model cannot explain.** If Σ_z' b'(z') = 0 (no sampled state reads
within τ ticks of the clock after this angle), the tick is not used: the belief becomes the
prediction Σ_z b̄(z) P(z' | z, a), and if that is empty too, the prior. The filter counts such
bumps (`surprises`); it never raises on an observation and never divides by zero.

All matrices are scipy.sparse, one (N, T·N) block row per angle (T tick values side by side), so
an update is one sparse vector-matrix product and the expected posterior entropy of every angle
(`expected_entropy`, for information gathering) one product per angle.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from bounce_gym.cells.outcomes import SAMPLE_FIELDS, BumpOutcomes
from bounce_gym.errors import ConfigError

#: default weight η of the tick-tolerant likelihood (module docstring)
DEFAULT_SLACK = 0.3
#: default ticks τ either side that the tolerant likelihood accepts
DEFAULT_TOLERANCE = 1
#: default restart probability ρ per bump
DEFAULT_RESTART = 1e-2


class BeliefFilter:
    """The histogram filter of the module docstring over the N cell numbers of ``outcomes``.

    Args:
        outcomes: the sampled GCM (P(z', t | z, a) is ``outcomes.transitions()``).
        prior: (N,) the initial belief b₀; None: uniform over the states that have samples.
        slack: η of the module docstring.
        tolerance: τ of the module docstring.
        restart: ρ of the module docstring.

    ``reset(prior)``, ``update(action, ticks)``; ``belief`` (read-only), ``most_likely``,
    ``mass_of(states)``, ``max_mass``, ``entropy``, ``expected_entropy()``.
    """

    def __init__(self, outcomes: BumpOutcomes, prior: np.ndarray | None = None,
                 slack: float = DEFAULT_SLACK, tolerance: int = DEFAULT_TOLERANCE,
                 restart: float = DEFAULT_RESTART) -> None:
        for name, value in (("slack", slack), ("restart", restart)):
            if isinstance(value, bool) or not 0.0 <= float(value) < 1.0:
                raise ConfigError(f"{name}: expected a number in [0, 1), got {value!r}")
        if isinstance(tolerance, bool) or not isinstance(tolerance, int | np.integer) \
                or tolerance < 0:
            raise ConfigError(f"tolerance: expected an integer >= 0, got {tolerance!r}")
        self.n_states = outcomes.n_cells
        self.n_actions = outcomes.n_actions
        self.slack, self.tolerance, self.restart = float(slack), int(tolerance), float(restart)
        z, a, nxt, t, p = outcomes.transitions()
        #: ticks 0 … n_ticks − 1 have a likelihood block (beyond the largest sampled + τ: none)
        self.n_ticks = int(t.max()) + 1 + self.tolerance if len(t) else 1
        self._prediction = outcomes.matrices()
        self._likelihood = [self._stacked(z[a == i], nxt[a == i], t[a == i], p[a == i])
                            for i in range(self.n_actions)]
        self._default_prior = self._checked_prior(prior, outcomes.states)
        self.surprises = 0
        self.reset()

    def _stacked(self, z, nxt, t, p) -> sp.csr_matrix:
        """(N, T·N) CSR: column block t holds L_t of one angle."""
        n, tau = self.n_states, self.tolerance
        shifts = np.arange(-tau, tau + 1)
        rows = np.concatenate([z, np.repeat(z, len(shifts))])
        ticks = np.concatenate([t, (t[:, None] + shifts).ravel()])
        cols = np.concatenate([nxt, np.repeat(nxt, len(shifts))])
        vals = np.concatenate([(1 - self.slack) * p,
                               np.repeat(self.slack * p / len(shifts), len(shifts))])
        ok = ticks >= 0
        return sp.csr_matrix((vals[ok], (rows[ok], ticks[ok] * n + cols[ok])),
                             shape=(n, self.n_ticks * n))  # duplicates are summed

    def _checked_prior(self, prior, states: np.ndarray) -> np.ndarray:
        if prior is None:
            out = np.zeros(self.n_states)
            out[states] = 1.0
        else:
            out = np.asarray(prior, dtype=np.float64).reshape(-1)
            if out.shape != (self.n_states,) or not np.all(np.isfinite(out)) \
                    or (out < 0).any():
                raise ConfigError(f"prior: expected {self.n_states} finite non-negative "
                                  "weights")
        if out.sum() <= 0:
            raise ConfigError("prior: expected a positive total weight")
        return out / out.sum()

    # -- the filter ---------------------------------------------------------------------------
    def reset(self, prior: np.ndarray | None = None) -> None:
        """Start from ``prior`` (None: the one given at construction); it also becomes the
        restart distribution b₀."""
        self.prior = self._default_prior if prior is None \
            else self._checked_prior(prior, np.arange(0))
        self._belief = self.prior.copy()
        self.surprises = 0

    def _action(self, action: int) -> int:
        if isinstance(action, bool) or not isinstance(action, int | np.integer) \
                or not 0 <= action < self.n_actions:
            raise ConfigError(f"action: expected an angle index in [0, {self.n_actions}), "
                              f"got {action!r}")
        return int(action)

    def _mixed(self) -> np.ndarray:
        return (1 - self.restart) * self._belief + self.restart * self.prior

    def update(self, action: int, ticks: int) -> None:
        """The bump after rotating by angle ``action`` and driving ``ticks`` ticks."""
        a = self._action(action)
        ticks = int(ticks)
        mixed = self._mixed()
        new = np.zeros(self.n_states)
        if 0 <= ticks < self.n_ticks:
            new = self._joint(a, mixed)[ticks]
        if new.sum() <= 0:
            self.surprises += 1
            new = self._prediction[a].T.dot(mixed)
            if new.sum() <= 0:
                new = self.prior.copy()
        self._belief = new / new.sum()

    def _joint(self, a: int, mixed: np.ndarray) -> np.ndarray:
        """(T, N): Σ_z mixed(z) L_t(z, z') for every tick count t of angle ``a``."""
        return self._likelihood[a].T.dot(mixed).reshape(self.n_ticks, self.n_states)

    # -- reading it ---------------------------------------------------------------------------
    @property
    def belief(self) -> np.ndarray:
        """(N,) b(z), read-only."""
        view = self._belief.view()
        view.flags.writeable = False
        return view

    @property
    def most_likely(self) -> int:
        """The decision state of largest belief (the lowest number on ties)."""
        return int(np.argmax(self._belief))

    @property
    def max_mass(self) -> float:
        return float(self._belief.max())

    def mass_of(self, states: Sequence[int] | np.ndarray) -> float:
        """The belief of a set of decision states."""
        return float(self._belief[np.unique(np.asarray(states, dtype=np.int64))].sum())

    @property
    def entropy(self) -> float:
        """Shannon entropy of the belief, in bits."""
        return _entropy(self._belief[None, :])[0]

    def expected_entropy(self) -> np.ndarray:
        """(|Φ|,) per angle, the expected entropy (bits) of the belief after the next bump,
        over the ticks the model predicts (Σ_t P(t) H(b'_t)); the lost mass and the ticks the
        model cannot produce are left out, as is the surprise fallback."""
        out = np.empty(self.n_actions)
        mixed = self._mixed()
        for a in range(self.n_actions):
            joint = self._joint(a, mixed)
            mass = joint.sum(axis=1)
            seen = mass > 0
            if not seen.any():
                out[a] = self.entropy
                continue
            posterior = joint[seen] / mass[seen, None]
            out[a] = float(mass[seen] @ _entropy(posterior) / mass[seen].sum())
        return out


def with_heading_offsets(parts: Sequence[BumpOutcomes], offsets: Sequence[float],
                         bin_width: float) -> BumpOutcomes:
    """One GCM over (offset class j, decision state z), numbered ``j·N + z``, from K sampled
    GCMs whose headings sit at bin centre + ``offsets[j]`` (radians, ascending within one bin).

    A robot that bounces by whole bins keeps its heading modulo the bin width, so that offset
    is a hidden variable the decision state does not hold; lumping all offsets together makes
    the bump-to-bump process far from Markov, and a filter on it confident and wrong. Each
    sample's next class is the offset nearest to the heading it drove with at its next bump
    (with bounce noise, the offset wanders between classes as the simulator says)."""
    n, k = parts[0].n_cells, len(parts)
    offsets = np.asarray(offsets, dtype=np.float64)
    fields: dict[str, list] = {f: [] for f in SAMPLE_FIELDS}
    for j, part in enumerate(parts):
        rest = np.mod(part.heading + bin_width / 2, bin_width) - bin_width / 2
        gap = np.abs(np.mod(rest[:, None] - offsets[None, :] + bin_width / 2, bin_width)
                     - bin_width / 2)
        nxt_class = np.argmin(gap, axis=1)
        fields["state"].append(j * n + part.state)
        fields["next_state"].append(np.where(part.next_state >= 0,
                                             nxt_class * n + part.next_state, -1))
        for f in ("action", "ticks", "start", "end", "heading"):
            fields[f].append(getattr(part, f))
    return BumpOutcomes(k * n, parts[0].angles,
                        *(np.concatenate(fields[f]) for f in SAMPLE_FIELDS))


def _entropy(rows: np.ndarray) -> np.ndarray:
    """Entropy in bits of each row of a (k, N) array of distributions."""
    safe = np.where(rows > 0, rows, 1.0)
    return -(rows * np.log2(safe)).sum(axis=1)
