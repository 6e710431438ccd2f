"""Sampled bump-to-bump outcomes of a cell model: the generalized cell mapping of a continuous
world, estimated from sample points (Hsu 1980; Hsu, *Cell-to-Cell Mapping*, 1987, ch. 11–12).

A **decision state** is a cell number ``z`` of a `CellModel` at a bump (the cell that holds the
contact point and the bin of the heading the robot drove with, `bounce_gym.cells.bump_states`);
an **action** is the index ``a`` of a bounce angle of Φ. From each decision state, ``n`` sample
poses were rotated by φ_a and driven to their next bump by a simulator
(`bounce_gym.dynamics.bump_sampler`). Every sample keeps its next state, the clock the robot
read at that bump (the ticks it drove), and its straight path (start and end points, heading), so
that goal regions chosen later can be tested on the paths themselves.

As in Hsu's GCM, the transition probability of (z, a) to an image is the fraction of the
samples of (z, a) that land in it: `transitions` gives the table P(z', ticks | z, a) as sparse
coordinate arrays, `matrices` the (N, N) row-sub-stochastic matrices P_a(z, z') of one angle each.
Samples whose simulation did not reach a bump within the simulator's limit have next state −1;
they count in the denominator, so a row's deficit is the probability of getting lost.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

#: world units by which a goal test widens the goal radius against rounding: the goal region
#: is the closed disk, so a drive that ends exactly on its circle (a cell centre at distance
#: ``goal_radius``, which the planners' goal cells count with the same slack) arrives,
#: although its entry point may compute one ulp past the drive's end. The env's test
#: (`bounce_gym.envs.tasks.navigation`), `BumpOutcomes.goal_hits` and the JAX task use it.
GOAL_SLACK = 1e-9

#: the per-sample arrays of `BumpOutcomes`, in the order they are stored
SAMPLE_FIELDS = ("state", "action", "next_state", "ticks", "start", "end", "heading")


@dataclass(frozen=True)
class BumpOutcomes:
    """The sample points of a GCM (module docstring). Arrays have one entry per sample.

    Attributes:
        n_cells: N, the cell numbers of the model (0 … N − 1).
        angles: (|Φ|,) the bounce angles, radians; ``action`` indexes them.
        state, action: the decision state and the angle index the sample started from.
        next_state: the decision state at the next bump (−1: none within the limit).
        ticks: the clock at the next bump (ticks driven since the rotation).
        start, end: (S, 2) the contact point it started from and the one it ended at.
        heading: the heading it drove with.
    """

    n_cells: int
    angles: np.ndarray
    state: np.ndarray
    action: np.ndarray
    next_state: np.ndarray
    ticks: np.ndarray
    start: np.ndarray
    end: np.ndarray
    heading: np.ndarray

    @property
    def n_actions(self) -> int:
        return len(self.angles)

    @property
    def states(self) -> np.ndarray:
        """The decision states that have samples, ascending."""
        return np.unique(self.state)

    def counts(self) -> np.ndarray:
        """(N, |Φ|) samples per state and action."""
        flat = self.state * self.n_actions + self.action
        return np.bincount(flat, minlength=self.n_cells * self.n_actions).reshape(
            self.n_cells, self.n_actions)

    def weights(self) -> np.ndarray:
        """(S,) the probability each sample stands for: 1 / (samples of its state and action)."""
        return 1.0 / self.counts()[self.state, self.action]

    def transitions(self, mask: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
        """The outcome table P(z', ticks | z, a) as coordinate arrays ``(z, a, z', ticks, p)``,
        one row per distinct outcome, sorted by (z, a, z', ticks); outcomes with z' = −1 are
        left out (the lost mass). With a boolean ``mask`` (S,) only those samples count (their
        share of all samples of (z, a)), e.g. the samples that miss a goal."""
        keep = self.next_state >= 0 if mask is None else (self.next_state >= 0) & mask
        w = self.weights()[keep]
        key = np.column_stack((self.state[keep], self.action[keep], self.next_state[keep],
                               self.ticks[keep]))
        rows, inverse = np.unique(key, axis=0, return_inverse=True)
        p = np.bincount(inverse.ravel(), weights=w, minlength=len(rows))
        return rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], p

    def matrices(self, mask: np.ndarray | None = None) -> list[sp.csr_matrix]:
        """Per angle, the (N, N) CSR matrix P_a(z, z') (sub-stochastic rows; ``mask`` as in
        `transitions`)."""
        z, a, nxt, _, p = self.transitions(mask)
        return [sp.csr_matrix((p[a == i], (z[a == i], nxt[a == i])),
                              shape=(self.n_cells, self.n_cells)) for i in range(self.n_actions)]

    def per_action(self, values: np.ndarray) -> np.ndarray:
        """(N, |Φ|) the mean of per-sample ``values`` over the samples of each (z, a)."""
        out = np.bincount(self.state * self.n_actions + self.action,
                          weights=values * self.weights(),
                          minlength=self.n_cells * self.n_actions)
        return out.reshape(self.n_cells, self.n_actions)

    def split(self, part: int, parts: int = 2) -> BumpOutcomes:
        """The samples of every (z, a) whose rank among them is ``part`` modulo ``parts``
        (independent sub-samples, for convergence checks)."""
        order = np.lexsort((np.arange(len(self.state)), self.action, self.state))
        flat = (self.state * self.n_actions + self.action)[order]
        first = np.searchsorted(flat, flat, side="left")
        rank = np.empty(len(order), dtype=np.int64)
        rank[order] = np.arange(len(order)) - first
        keep = rank % parts == part
        return BumpOutcomes(self.n_cells, self.angles,
                            *(getattr(self, f)[keep] for f in SAMPLE_FIELDS))

    def total_variation(self, other: BumpOutcomes) -> np.ndarray:
        """(N, |Φ|) the total-variation distance between the next-state distributions of two
        estimates, where both have samples (NaN elsewhere)."""
        both = (self.counts() > 0) & (other.counts() > 0)
        out = np.full(both.shape, np.nan)
        diff = [abs(m - o) for m, o in zip(self.matrices(), other.matrices(), strict=True)]
        lost = [self._lost(), other._lost()]
        for a, d in enumerate(diff):
            tv = 0.5 * (np.asarray(d.sum(axis=1)).ravel() + np.abs(lost[0][:, a] - lost[1][:, a]))
            out[both[:, a], a] = tv[both[:, a]]
        return out

    def _lost(self) -> np.ndarray:
        return self.per_action((self.next_state < 0).astype(np.float64))

    def goal_hits(self, position: np.ndarray, heading: float, radius: float,
                  tolerance: float) -> np.ndarray:
        """(S,) whether each sample's straight path passes through the disk of ``radius``
        around ``position`` while its heading is within ``tolerance`` of ``heading`` (radians)
        — the goal test of `bounce_gym.envs.tasks.navigation`."""
        err = np.abs(np.mod(self.heading - heading + np.pi, 2 * np.pi) - np.pi)
        rel = self.start - np.asarray(position, dtype=np.float64)
        seg = self.end - self.start
        length = np.hypot(seg[:, 0], seg[:, 1])
        safe = np.where(length > 0, length, 1.0)
        b = np.einsum("ij,ij->i", rel, seg) / safe
        c = np.einsum("ij,ij->i", rel, rel) - (radius + GOAL_SLACK)**2
        disc = b * b - c
        entry = -b - np.sqrt(np.maximum(disc, 0.0))
        crosses = (length > 0) & (disc >= 0) & (entry >= 0) & (entry <= length)
        return (err <= tolerance) & ((c <= 0) | crosses)

    # -- storage ------------------------------------------------------------------------------
    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays to store (`from_arrays` reads them back)."""
        out = {f: np.ascontiguousarray(getattr(self, f)) for f in SAMPLE_FIELDS}
        out["angles"] = np.asarray(self.angles, dtype=np.float64)
        return out

    @classmethod
    def from_arrays(cls, n_cells: int, arrays: dict[str, np.ndarray]) -> BumpOutcomes:
        """Outcomes from `arrays`; raises ValueError when they are not consistent."""
        state = np.asarray(arrays["state"], dtype=np.int64)
        s = len(state)
        shapes = {"action": (s,), "next_state": (s,), "ticks": (s,), "start": (s, 2),
                  "end": (s, 2), "heading": (s,)}
        for name, shape in shapes.items():
            if np.shape(arrays[name]) != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {np.shape(arrays[name])}")
        angles = np.asarray(arrays["angles"], dtype=np.float64).reshape(-1)
        out = cls(int(n_cells), angles, state,
                  np.asarray(arrays["action"], dtype=np.int64),
                  np.asarray(arrays["next_state"], dtype=np.int64),
                  np.asarray(arrays["ticks"], dtype=np.int64),
                  np.asarray(arrays["start"], dtype=np.float64),
                  np.asarray(arrays["end"], dtype=np.float64),
                  np.asarray(arrays["heading"], dtype=np.float64))
        if s and (state.min() < 0 or state.max() >= n_cells or out.next_state.max() >= n_cells
                  or out.next_state.min() < -1 or out.action.min() < 0
                  or out.action.max() >= len(angles) or out.ticks.min() < 0
                  or not np.all(np.isfinite(out.heading))):
            raise ValueError("sample arrays out of range")
        return out
