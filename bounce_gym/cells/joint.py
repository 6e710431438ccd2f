"""The joint cell model of m bouncing robots."""

from __future__ import annotations

import math

import numpy as np

from bounce_gym.cells.conflicts import crowded, resolve_moves, too_close
from bounce_gym.cells.model import CellModel
from bounce_gym.errors import ConfigError

NEIGHBORS = ("rotation", "full")


class JointCellModel:
    """The joint cell map of m bouncing robots on one `CellModel`.

    Args:
        model: the per-robot cell model.
        angles_per_robot: bounce angle φ_i in degrees per robot (a length-m sequence; a scalar
            is not accepted because m is taken from it). Each must be a multiple of the bins.
        collisions: robot–robot collisions block (the coverage task); ``False`` = the robots
            ignore each other and may share cells.
        min_sep_cells: with collisions, the Chebyshev distance at or below which two robots
            collide (0 = the same cell; module docstring).
    """

    def __init__(self, model: CellModel, angles_per_robot, collisions: bool = True,
                 min_sep_cells: int = 0) -> None:
        angles = [float(a) for a in np.atleast_1d(np.asarray(angles_per_robot, dtype=float))]
        if not angles:
            raise ConfigError("angles_per_robot: expected one angle per robot")
        self.model = model
        self.m = len(angles)
        self.angles = angles
        self.phi_bins = np.array([model.angle_bins(math.radians(a), "bounce angle") % model.n_bins
                                  for a in angles], dtype=np.int64)
        if np.any(self.phi_bins == 0):
            raise ConfigError("bounce angle: a multiple of 360° never leaves the wall")
        self.collisions = bool(collisions)
        if self.collisions and model.n_positions < self.m:
            raise ConfigError(f"{self.m} robots do not fit in {model.n_positions} free cells")
        close = too_close(model.position_rc, min_sep_cells)  # validates min_sep_cells
        self.min_sep_cells = int(min_sep_cells)
        self.close = close if self.collisions and self.min_sep_cells > 0 else None
        self.n_robot_cells = model.n_cells
        self.n_joint = model.n_cells ** self.m  # a Python int: may exceed int64

    # -- numbering --------------------------------------------------------------------------
    def encode(self, joint: np.ndarray) -> np.ndarray:
        """Mixed-radix joint index ``Σ_i z_i · N^i`` of joint cells (…, m); needs N^m < 2^63."""
        if self.n_joint >= 2 ** 63:
            raise ConfigError(f"encode: {self.n_robot_cells}^{self.m} joint cells overflow int64; "
                              "use the tuples of per-robot cells")
        radix = self.n_robot_cells ** np.arange(self.m, dtype=np.int64)
        return np.asarray(joint, dtype=np.int64) @ radix

    def decode(self, index: np.ndarray) -> np.ndarray:
        """Joint cells (…, m) of mixed-radix indices."""
        index = np.asarray(index, dtype=np.int64)
        radix = self.n_robot_cells ** np.arange(self.m, dtype=np.int64)
        return (index[..., None] // radix) % self.n_robot_cells

    def index_of(self, joint) -> int:
        """The mixed-radix joint index of one joint cell as a Python int (any m)."""
        n = self.n_robot_cells
        return sum(int(z) * n ** i for i, z in enumerate(joint))

    def from_poses(self, positions, headings_deg) -> np.ndarray:
        """Joint cell (m,) of robot positions (m, 2) and headings in degrees (m,)."""
        z = self.model.cell_of(np.asarray(positions, float), np.radians(headings_deg))
        if np.any(z < 0):
            raise ConfigError("from_poses: a robot is not in a free cell")
        return z

    def valid(self, joint: np.ndarray) -> np.ndarray:
        """Joint cells (batch, m) in X_free: with collisions, no two robots share a position."""
        joint = np.atleast_2d(joint)
        ok = np.all((joint >= 0) & (joint < self.n_robot_cells), axis=1)
        if self.collisions and self.m > 1:
            ok &= ~crowded(np.where(ok[:, None], joint, 0) % self.model.n_positions, self.close)
        return ok

    # -- the map ----------------------------------------------------------------------------
    def plan(self, joint: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(positions, bins, final target or -1, robot-collision pairs per row) of a batch."""
        joint = np.atleast_2d(np.asarray(joint, dtype=np.int64))
        p, k = self.model.decode(joint)
        target0 = self.model.targets[k, p]
        if not self.collisions or self.m == 1:
            return p, k, target0, np.zeros(len(joint), dtype=np.int64)
        stays, _, pairs = resolve_moves(p, target0, self.model.position_rc, self.close)
        return p, k, np.where(stays, -1, target0), pairs

    def step(self, joint: np.ndarray, return_collisions: bool = False):
        """Next joint cells (batch, m) of joint cells (batch, m) or (m,) — Eq. 6.

        With ``return_collisions``, also the number of colliding robot pairs per row.
        """
        joint = np.asarray(joint, dtype=np.int64)
        single = joint.ndim == 1
        p, k, target, pairs = self.plan(joint)
        blocked = target < 0
        new_p = np.where(blocked, p, target)
        new_k = np.where(blocked, (k + self.phi_bins) % self.model.n_bins, k)
        nxt = self.model.cell_id(new_p, new_k)
        if single:
            nxt, pairs = nxt[0], pairs[0]
        return (nxt, pairs) if return_collisions else nxt

    def neighbors(self, joint: np.ndarray, mode: str = "rotation") -> np.ndarray:
        """Valid neighbours (n, m) of one joint cell: ±Δθ of one robot (2m), and with ``"full"``
        also ±1 cell in x or y of one robot (6m at most). Order: robot 0 +Δθ, −Δθ, robot 1 …"""
        if mode not in NEIGHBORS:
            raise ConfigError(f"neighbors: expected one of {NEIGHBORS}, got {mode!r}")
        joint = np.asarray(joint, dtype=np.int64)
        p, k = self.model.decode(joint)
        nb = self.model.n_bins
        out = []
        for i in range(self.m):
            for d in (1, -1):
                q = joint.copy()
                q[i] = self.model.cell_id(p[i], (k[i] + d) % nb)
                out.append(q)
            if mode == "full":
                r, c = self.model.position_rc[p[i]]
                for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0)):
                    rr, cc = r + dr, c + dc
                    if not (0 <= rr < self.model.rows and 0 <= cc < self.model.cols):
                        continue
                    pi = self.model.position_index[rr, cc]
                    if pi < 0:
                        continue
                    q = joint.copy()
                    q[i] = self.model.cell_id(pi, k[i])
                    out.append(q)
        out = np.array(out, dtype=np.int64).reshape(-1, self.m)
        return out[self.valid(out)]

    def random_joint(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Random valid joint cells (n, m): distinct free cells (with collisions; at least
        ``min_sep_cells`` + 1 apart, by rejection), uniform bins."""
        npos = self.model.n_positions
        out = np.empty((n, self.m), dtype=np.int64)
        for row in range(n):
            for _ in range(10_000):
                if self.collisions:
                    p = rng.choice(npos, self.m, replace=False)
                else:
                    p = rng.integers(0, npos, self.m)
                k = rng.integers(0, self.model.n_bins, self.m)
                out[row] = self.model.cell_id(p, k)
                if self.valid(out[row])[0]:
                    break
            else:
                raise ConfigError(f"could not place {self.m} robots min_sep_cells = "
                                  f"{self.min_sep_cells} apart in 10,000 tries")
        return out

    def reachable_positions(self, start_positions) -> np.ndarray:
        """Free position cells reachable by king moves allowed by the corner rule from any of
        ``start_positions`` (a boolean mask over positions)."""
        adj = self.model.targets  # (n_bins, n_positions)
        seen = np.zeros(self.model.n_positions, dtype=bool)
        frontier = np.unique(np.asarray(start_positions, dtype=np.int64))
        seen[frontier] = True
        while len(frontier):
            nxt = adj[:, frontier].ravel()
            nxt = np.unique(nxt[nxt >= 0])
            nxt = nxt[~seen[nxt]]
            seen[nxt] = True
            frontier = nxt
        return seen


