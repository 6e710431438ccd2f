"""The discrete cell-to-cell model of the bouncing robot (Alam, Bobadilla & Shell).

State space: free position cells x orientation bins. A position cell is free iff its centre lies in
the free space (or, for a disk robot, its configuration space; docs/choices/cell_model.md, "Free cells and the
endpoint test"). Bins are centred at θ_k = k·Δθ, Δθ = 360° / n_bins, counter-clockwise from East.

**Numbering** (consistent with the cell ids of thesis §3.5.1, e.g. cell 104 of the 48-position lab
faces North): orientation-major, East layer first,
``z = k · N_pos + p`` with ``p`` the row-major index of the position cell counted from the
bottom-left (y up). Indices are 0-based inside the package; the papers' 1-based ids are ``z + 1``.

**Next cell** (thesis Eq. 2.4 / Alam, Bobadilla & Shell 2018, Eq. 4, with the choices of
docs/choices/cell_model.md "Bumps rotate in place and take one tick", "The state resets to the cell centre
every step" and "Unit steps are king moves, with a symmetric tie rule"):

* from the centre of the cell, step (cos θ, sin θ): on a unit grid this always lands in one of the
  8 neighbours (a king move); per axis the offset is +1 if the component is ≥ 0.5 − 1e-9, −1 if it
  is ≤ −0.5 + 1e-9, else 0 — an explicit tie rule for 30°, 60°, … that is symmetric under 90°
  rotations (``sin 30°`` is 0.49999999999999994 in floating point);
* if the target cell is free (and, by ``corner_rule``, the move does not squeeze between blocked
  cells) the robot moves there keeping its bin — observation 0;
* otherwise it stays and rotates counter-clockwise by φ — a bump, observation 1. Cells outside the
  grid count as blocked. The position resets to the cell centre every step.

``corner_rule`` (docs/choices/multirobot.md, "Diagonal moves and the corner rule"): ``"target_only"`` (default;
the localization and navigation papers' endpoint test, corner cutting allowed), ``"no_squeeze"`` (a
diagonal move is blocked when both side cells are blocked), ``"strict"`` (blocked when either side
cell is).

The generalized cell mapping (GCM, thesis §3.3.3; Alam, Bobadilla & Shell 2017, Sec. III-B)
replaces the rotation by a distribution: the
nominal bin with probability r and each of the 2·n_ε other bins within ±ε with (1 − r) / (2·n_ε).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

CORNER_RULES = ("target_only", "no_squeeze", "strict")
_TIE = 1e-9
#: The most states (grid cells x orientation bins) of a `CellModel`: 2^24, whose next-cell table
#: takes 128 MiB (the grid itself is at most `bounce_gym.worlds.world.MAX_GRID_CELLS` cells).
MAX_CELL_STATES = 1 << 24


def check_model_size(world: World, cell_size: float, n_bins: int, field: str = "cell_size"
                     ) -> None:
    """Raise `ConfigError` naming ``field`` if the cell model of ``world`` at ``cell_size``
    with ``n_bins`` bins would have a grid of more than
    `bounce_gym.worlds.world.MAX_GRID_CELLS` cells or more than `MAX_CELL_STATES` states
    (counting blocked cells: checked before the grid is built)."""
    world.check_grid(field, cell_size)
    world.check_grid(field, cell_size, MAX_CELL_STATES, per_cell=n_bins,
                     what="cell model states")


def king_offset(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Grid offsets (d_col, d_row) of a unit step from a cell centre at headings ``theta``."""
    def snap(v: np.ndarray) -> np.ndarray:
        return np.where(v >= 0.5 - _TIE, 1, np.where(v <= -0.5 + _TIE, -1, 0))

    theta = np.asarray(theta, dtype=np.float64)
    return snap(np.cos(theta)), snap(np.sin(theta))


def king_step(theta: float) -> tuple[int, int]:
    """`king_offset` of one heading (radians) in Python floats, (d_col, d_row): the same tie
    rule on `math`'s cosine and sine (a lone robot's hot path)."""
    def snap(v: float) -> int:
        return 1 if v >= 0.5 - _TIE else -1 if v <= -0.5 + _TIE else 0

    return snap(math.cos(theta)), snap(math.sin(theta))


def _is_free(free: np.ndarray, row: np.ndarray, col: np.ndarray) -> np.ndarray:
    rows, cols = free.shape
    inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
    ok = np.zeros(len(row), dtype=bool)
    ok[inside] = free[row[inside], col[inside]]
    return ok


def king_move_allowed(free: np.ndarray, row: np.ndarray, col: np.ndarray, drow: int, dcol: int,
                      corner_rule: str) -> np.ndarray:
    """Whether the king move (``drow``, ``dcol``) from each cell (``row``, ``col``) of the
    occupancy grid ``free`` (True = free; cells outside the grid are blocked) lands on a free
    cell and, for a diagonal move, passes ``corner_rule`` (see the module docstring)."""
    ok = _is_free(free, row + drow, col + dcol)
    if drow and dcol and corner_rule != "target_only":
        side_a, side_b = _is_free(free, row + drow, col), _is_free(free, row, col + dcol)
        ok &= (side_a | side_b) if corner_rule == "no_squeeze" else (side_a & side_b)
    return ok


class CellModel:
    """Position cells x orientation bins of a world, with the deterministic and stochastic maps.

    Args:
        world: the workspace.
        cell_size: side of a position cell (one step of the robot).
        n_bins: orientation bins; 360 must be divisible by it (8 for 45°, 360 for 1°).
        robot_radius: discretise the configuration space of a disk robot of this radius.
        corner_rule: see the module docstring.
    """

    def __init__(self, world: World, cell_size: float = 1.0, n_bins: int = 8,
                 robot_radius: float = 0.0, corner_rule: str = "target_only") -> None:
        if isinstance(n_bins, bool) or not isinstance(n_bins, int | np.integer) or n_bins < 1 \
                or 360 % n_bins:
            raise ConfigError(f"n_bins: expected a divisor of 360 (e.g. 4, 8, 360), got {n_bins!r}")
        if corner_rule not in CORNER_RULES:
            raise ConfigError(f"corner_rule: expected one of {CORNER_RULES}, got {corner_rule!r}")
        self.world = world
        self.cell_size = float(cell_size)
        self.n_bins = int(n_bins)
        self.robot_radius = float(robot_radius)
        self.corner_rule = corner_rule
        if not (math.isfinite(self.cell_size) and self.cell_size > 0):
            raise ConfigError(f"cell_size: expected a finite number > 0, got {cell_size!r}")
        check_model_size(world, self.cell_size, self.n_bins)
        self.free = world.occupancy(self.cell_size, self.robot_radius)
        self.rows, self.cols = self.free.shape
        rc = np.argwhere(self.free)  # sorted by row (bottom first), then column
        if len(rc) == 0:
            raise ConfigError(f"world {world.name!r} has no free cell of size {cell_size} "
                              f"for a robot of radius {robot_radius}")
        self.position_rc = rc
        self.n_positions = len(rc)
        self.n_cells = self.n_positions * self.n_bins
        self.position_index = np.full(self.free.shape, -1, dtype=np.int64)
        self.position_index[rc[:, 0], rc[:, 1]] = np.arange(self.n_positions)
        xmin, ymin = world.bounds[:2]
        self.origin = (xmin, ymin)
        self.centres = np.column_stack((xmin + (rc[:, 1] + 0.5) * self.cell_size,
                                        ymin + (rc[:, 0] + 0.5) * self.cell_size))
        self.bin_width = 2 * math.pi / self.n_bins
        self.targets = self._targets()  # (n_bins, n_positions): target position or -1 (bump)

    # -- numbering --------------------------------------------------------------------------
    def cell_id(self, position: np.ndarray, bin_: np.ndarray) -> np.ndarray:
        """Cell number z of position index p and bin k."""
        return np.asarray(bin_) * self.n_positions + np.asarray(position)

    def decode(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position index, bin) of cell numbers z."""
        z = np.asarray(z)
        return z % self.n_positions, z // self.n_positions

    def configuration(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cell centres (…, 2) and bin headings (radians) of cell numbers z."""
        p, k = self.decode(z)
        return self.centres[p], k * self.bin_width

    def cell_of(self, position: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """Cell number containing each (x, y) with the nearest heading bin; -1 if not free."""
        pos = np.asarray(position, dtype=np.float64).reshape(-1, 2)
        col = np.floor((pos[:, 0] - self.origin[0]) / self.cell_size).astype(np.int64)
        row = np.floor((pos[:, 1] - self.origin[1]) / self.cell_size).astype(np.int64)
        inside = (row >= 0) & (row < self.rows) & (col >= 0) & (col < self.cols)
        p = np.full(len(pos), -1, dtype=np.int64)
        p[inside] = self.position_index[row[inside], col[inside]]
        k = self.bin_of(heading)
        return np.where(p >= 0, self.cell_id(np.maximum(p, 0), k), -1)

    def bin_of(self, heading: np.ndarray) -> np.ndarray:
        """Nearest bin of headings (radians)."""
        return np.rint(np.asarray(heading, dtype=np.float64).reshape(-1) / self.bin_width).astype(
            np.int64) % self.n_bins

    def angle_bins(self, angle: float, field: str = "angle") -> int:
        """An angle (radians) as a whole number of bins; it must be a multiple of the bin width."""
        bins = angle / self.bin_width
        if not math.isfinite(bins) or abs(bins - round(bins)) > 1e-6:
            raise ConfigError(f"{field}: {math.degrees(angle):g}° is not a multiple of the "
                              f"{math.degrees(self.bin_width):g}° orientation bins")
        return int(round(bins))

    # -- the map ----------------------------------------------------------------------------
    def _targets(self) -> np.ndarray:
        dcol, drow = king_offset(np.arange(self.n_bins) * self.bin_width)
        row, col = self.position_rc[:, 0], self.position_rc[:, 1]
        out = np.empty((self.n_bins, self.n_positions), dtype=np.int64)
        for k in range(self.n_bins):
            out[k] = self._target(row, col, int(drow[k]), int(dcol[k]))
        return out

    def _target(self, row, col, drow: int, dcol: int) -> np.ndarray:
        ok = king_move_allowed(self.free, row, col, drow, dcol, self.corner_rule)
        out = np.full(len(row), -1, dtype=np.int64)
        out[ok] = self.position_index[row[ok] + drow, col[ok] + dcol]
        return out

    def next_cell(self, z: np.ndarray, phi: float) -> tuple[np.ndarray, np.ndarray]:
        """Next cell of every z (vectorised) under bounce angle ``phi`` (radians), and the
        observation: True where the step is a bump (rotation in place)."""
        p, k = self.decode(np.asarray(z, dtype=np.int64))
        target = self.targets[k, p]
        bump = target < 0
        rotated = (k + self.angle_bins(phi, "bounce angle")) % self.n_bins
        nxt = np.where(bump, self.cell_id(p, rotated), self.cell_id(np.maximum(target, 0), k))
        return nxt, bump

    def successor(self, phi: float) -> tuple[np.ndarray, np.ndarray]:
        """The simple cell mapping C for one bounce angle: successor (N,) and bump flag (N,)."""
        if self.angle_bins(phi, "bounce angle") % self.n_bins == 0:
            raise ConfigError("bounce angle: a multiple of 360° never leaves the wall")
        return self.next_cell(np.arange(self.n_cells, dtype=np.int64), phi)

    def transition_matrix(self, phi: float, eps: float = 0.0, r: float = 1.0) -> sp.csr_matrix:
        """The generalized cell mapping: a row-stochastic sparse (N, N) matrix.

        Forward cells move with probability 1. Bump cells rotate to the nominal bin with
        probability ``r`` and to each of the other bins within ±``eps`` (radians, a multiple of
        the bin width) with probability (1 − r) / (2·n_ε); with ``eps = 0`` the rotation is exact.
        """
        if not 0.0 <= r <= 1.0:
            raise ConfigError(f"r: the reliability must be in [0, 1], got {r!r}")
        n_eps = self.angle_bins(eps, "eps") if eps else 0
        if n_eps < 0:
            raise ConfigError(f"eps: expected >= 0, got {math.degrees(eps):g}°")
        succ, bump = self.successor(phi)
        z = np.arange(self.n_cells, dtype=np.int64)
        rows, cols, data = [z[~bump]], [succ[~bump]], [np.ones(int((~bump).sum()))]
        p, _ = self.decode(z[bump])
        _, nominal = self.decode(succ[bump])
        for j in range(-n_eps, n_eps + 1):
            weight = r if j == 0 else (1.0 - r) / (2 * n_eps)
            if n_eps == 0:
                weight = 1.0
            if weight == 0.0:
                continue
            rows.append(z[bump])
            cols.append(self.cell_id(p, (nominal + j) % self.n_bins))
            data.append(np.full(len(p), weight))
        matrix = sp.coo_matrix(
            (np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.n_cells, self.n_cells),
        )
        return matrix.tocsr()  # duplicates (when 2·n_ε + 1 > n_bins) are summed
