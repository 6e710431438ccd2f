"""Robot–robot conflicts on the cell grid (thesis Eq. 3.9; the rules are a choice
where Alam & Bobadilla 2020 is silent: docs/choices/multirobot.md, "Robot–robot conflicts on the grid").

Each robot proposes its target cell (−1 if an obstacle blocks it). A robot that wants to move is
also blocked when its target is another moving robot's target, when two robots would swap cells,
when two diagonal moves cross (`crossing`: robot A from (r, c) to (r+1, c+1) while robot B goes
from (r, c+1) to (r+1, c) — both robots would be at the shared midpoint half-way through the
tick), or when its target is the cell of a robot that stays — iterated to a fixpoint. Moving into
a cell that another robot is vacating is allowed. A blocked robot stays and rotates, whatever the
rule that blocked it. Vectorised over a batch of joint states; shared by the
``cell`` backend of the environments and the joint cell model of the multi-robot planners.

**Minimum separation** (``min_sep_cells`` s, for cells smaller than the robot diameter):
"the same cell" becomes "within Chebyshev distance s" (`too_close`) — a move is blocked when its
target is that close to another mover's target or to a stayer's cell; s = 0 is the rule above.
The relation is a `CloseCells`, indexed like the (n, n) bool matrix but computed from the cells'
grid coordinates on lookup: memory O(n), so maps of 10⁶ cells build.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.spatial import cKDTree

from bounce_gym.errors import ConfigError

#: Largest n² of a dense `CloseCells` matrix (``np.asarray``): 10⁸ bytes.
_DENSE_LIMIT = 10**8


class CloseCells:
    """Which pairs of position cells are too close: the `too_close` relation, looked up on demand.

    ``close[i, j]`` (integer index arrays that broadcast, like a NumPy matrix's fancy indexing)
    is True where position cells ``i`` and ``j`` are within Chebyshev distance ``min_sep_cells``
    — the entries of the (n, n) matrix, computed from the two cells' grid coordinates instead of
    stored: memory O(n), whatever the map's size. ``np.asarray(close)`` builds the dense matrix
    (small maps only) and `pairs` lists the close pairs with a KD-tree (O(n + pairs) memory).
    """

    __slots__ = ("min_sep_cells", "position_rc")

    def __init__(self, position_rc: np.ndarray, min_sep_cells: int) -> None:
        self.position_rc = np.asarray(position_rc).reshape(-1, 2)
        self.min_sep_cells = int(min_sep_cells)

    @property
    def shape(self) -> tuple[int, int]:
        n = len(self.position_rc)
        return n, n

    def __getitem__(self, index: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        i, j = index
        row, col = self.position_rc.T  # axis by axis: no (..., 2) temporaries
        out = np.abs(row[i] - row[j]) <= self.min_sep_cells
        out &= np.abs(col[i] - col[j]) <= self.min_sep_cells
        return out

    def pairs(self) -> np.ndarray:
        """(k, 2) index pairs ``i < j`` of the distinct cells that are too close, sorted: a
        KD-tree query (`scipy.spatial.cKDTree`) in O(n + pairs) memory."""
        tree = cKDTree(self.position_rc.astype(np.float64))
        out = tree.query_pairs(self.min_sep_cells, p=np.inf, output_type="ndarray")
        return out[np.lexsort((out[:, 1], out[:, 0]))].astype(np.int64, copy=False)

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        """The dense (n, n) bool matrix (n² bytes: for small maps)."""
        n = len(self.position_rc)
        if n * n > _DENSE_LIMIT:
            raise ConfigError(f"too_close: a dense {n} x {n} matrix is too large; index it "
                              "(close[i, j]) or list its pairs() instead")
        out = np.eye(n, dtype=bool)
        i, j = self.pairs().T
        out[i, j] = out[j, i] = True
        return out if dtype is None else out.astype(dtype)

    def __repr__(self) -> str:
        return f"CloseCells(n={len(self.position_rc)}, min_sep_cells={self.min_sep_cells})"


def too_close(position_rc: np.ndarray, min_sep_cells: int = 0) -> CloseCells:
    """Which two robots would collide at position cells with grid coordinates ``position_rc``
    (n, 2): Chebyshev distance ≤ ``min_sep_cells`` (0: the same cell). A `CloseCells` — index
    it like the (n, n) bool matrix, ``close[i, j]``; it stores only the coordinates."""
    if isinstance(min_sep_cells, bool) or not isinstance(min_sep_cells, int | np.integer) \
            or min_sep_cells < 0:
        raise ConfigError(f"min_sep_cells: expected a non-negative integer, got {min_sep_cells!r}")
    return CloseCells(position_rc, min_sep_cells)


def crowded(position: np.ndarray, close: CloseCells | None = None) -> np.ndarray:
    """(batch,) bool: some two robots of a joint state (batch, m) of position cells collide —
    share a cell, or with a `too_close` relation are within its separation."""
    position = np.atleast_2d(position)
    m = position.shape[1]
    if close is None:
        ps = np.sort(position, axis=1)
        return np.any(ps[:, 1:] == ps[:, :-1], axis=1)
    near = close[position[:, :, None], position[:, None, :]] & ~np.eye(m, dtype=bool)
    return near.any(axis=(1, 2))


def crossing(from_a: np.ndarray, to_a: np.ndarray, from_b: np.ndarray, to_b: np.ndarray
             ) -> np.ndarray:
    """Whether two simultaneous king moves cross diagonally (grid coordinates (..., 2), which
    broadcast; a robot that stays has ``to == from``).

    The moves take the same tick at constant speed, so half-way both robots are at their move's
    midpoint: the moves cross when the midpoints coincide and the robots do not simply swap
    cells (a swap is its own rule). For king moves this is exactly the pair of crossing
    diagonals of one 2×2 block; a robot that stays never crosses anyone.
    """
    from_a, to_a, from_b, to_b = (np.asarray(x) for x in (from_a, to_a, from_b, to_b))
    same_mid = (from_a + to_a == from_b + to_b).all(axis=-1)
    swap = ((from_a == to_b) & (to_a == from_b)).all(axis=-1)
    return same_mid & ~swap


@functools.cache
def _pair_masks(m: int) -> tuple[np.ndarray, np.ndarray]:
    """(others, upper) of m robots, read-only (m, m) bool: i ≠ j, and i < j."""
    others, upper = ~np.eye(m, dtype=bool), np.triu(np.ones((m, m), dtype=bool), 1)
    others.flags.writeable = upper.flags.writeable = False
    return others, upper


def resolve_moves(position: np.ndarray, target: np.ndarray, position_rc: np.ndarray,
                  close: CloseCells | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which robots stay, given their cells and proposed targets.

    Args:
        position: (batch, m) current position cell of every robot.
        target: (batch, m) proposed target position cell, −1 where an obstacle blocks the move.
        position_rc: (n_positions, 2) grid coordinates of the position cells (for `crossing`).
        close: the `too_close` relation of a minimum separation; ``None`` = the same cell only.

    Returns:
        stays (batch, m) bool; blocker (batch, m): for a robot stopped by another robot, the
        robot it conflicts with (the lowest index), else −1; pairs (batch,): colliding pairs.
    """
    position = np.atleast_2d(position)
    target = np.atleast_2d(target)
    m = position.shape[1]
    stays = target < 0
    if m == 1:
        return stays, np.full(position.shape, -1, dtype=np.int64), np.zeros(len(position), np.int64)
    others, upper = _pair_masks(m)
    wants = ~stays
    if close is None:
        same = target[:, :, None] == target[:, None, :]
        at = target[:, :, None] == position[:, None, :]  # i's target = j's cell
    else:
        t = np.where(wants, target, 0)
        same = close[t[:, :, None], t[:, None, :]]
        at = close[t[:, :, None], position[:, None, :]]
    same &= wants[:, :, None] & wants[:, None, :] & others
    at &= wants[:, :, None] & others
    swap = (target[:, :, None] == position[:, None, :]) & wants[:, :, None]
    swap &= np.swapaxes(swap, 1, 2)
    rc_from = position_rc[position]
    rc_to = position_rc[np.where(wants, target, position)]
    # swapping or crossing: the two robots would pass through each other
    through = swap | (crossing(rc_from[:, :, None], rc_to[:, :, None], rc_from[:, None],
                               rc_to[:, None]) & others)
    movers = same | through  # conflicts that block i while both i and j move
    while True:  # i is newly blocked by a moving j's conflict or by moving at a staying j
        newly = ~stays & np.where(stays[:, None, :], at, movers).any(axis=2)
        if not newly.any():
            break
        stays |= newly
    contact = (stays & wants)[:, :, None] & (movers | (at & stays[:, None, :]))
    blocker = np.where(contact.any(axis=2), contact.argmax(axis=2), -1).astype(np.int64)
    pairs = ((contact | np.swapaxes(contact, 1, 2)) & upper).sum(axis=(1, 2))
    return stays, blocker, pairs
