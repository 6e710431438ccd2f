"""Robot–robot conflicts on the cell grid (thesis Eq. 3.9; the rules of spec 002 §8.4).

Each robot proposes its target cell (−1 if an obstacle blocks it). A robot that wants to move is
also blocked when its target is another moving robot's target, when two robots would swap cells,
or when its target is the cell of a robot that stays — iterated to a fixpoint. Moving into a cell
that another robot is vacating is allowed. Vectorised over a batch of joint states; shared by the
``cell`` backend of the environments and the joint cell model of the multi-robot planners.
"""

from __future__ import annotations

import numpy as np


def resolve_moves(position: np.ndarray, target: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which robots stay, given their cells and proposed targets.

    Args:
        position: (batch, m) current position cell of every robot.
        target: (batch, m) proposed target position cell, −1 where an obstacle blocks the move.

    Returns:
        stays (batch, m) bool; blocker (batch, m): for a robot stopped by another robot, the
        robot it conflicts with (the lowest index), else −1; pairs (batch,): colliding pairs.
    """
    position = np.atleast_2d(position)
    target = np.atleast_2d(target)
    m = position.shape[1]
    stays = target < 0
    blocker = np.full(position.shape, -1, dtype=np.int64)
    if m == 1:
        return stays, blocker, np.zeros(len(position), dtype=np.int64)
    eye = np.eye(m, dtype=bool)[None]
    wants = ~stays
    same = (target[:, :, None] == target[:, None, :]) & wants[:, :, None] & ~eye
    at = (target[:, :, None] == position[:, None, :]) & wants[:, :, None]  # i's target = j's cell
    swap = at & np.swapaxes(at, 1, 2)
    while True:
        moving = ~stays
        mm = moving[:, :, None] & moving[:, None, :]
        newly = moving & (np.any(same & mm, axis=2) | np.any(swap & mm, axis=2)
                          | np.any(at & stays[:, None, :], axis=2))
        if not newly.any():
            break
        stays |= newly
    by_robot = stays & wants
    contact = by_robot[:, :, None] & (same | swap | (at & stays[:, None, :]))
    has = contact.any(axis=2)
    blocker[has] = np.argmax(contact, axis=2)[has]
    pairs = np.triu(contact | np.swapaxes(contact, 1, 2), 1).sum(axis=(1, 2))
    return stays, blocker, pairs
