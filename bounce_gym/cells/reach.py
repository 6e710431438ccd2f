"""Which poses a bouncing robot can pass, and after how few bounces, on the cell model.

On the deterministic cell model (`CellModel`, exact rotations) a robot in bounce mode decides
only at *decision poses*: poses whose next king move is blocked, where it bumps, turns in place
by an angle of Φ and drives to the next decision pose. A pose ``g`` is *passed* by a bounce when
the drive after it goes through ``g`` — the rotated pose at the bump included, with the heading
of the drive — which is what the navigation tasks count as reaching a goal pose at a cell centre
(Alam, Bobadilla & Shell 2017, Sec. IV: the plan reaches x_G when the trajectory passes it).

`BounceReach` tabulates, for every decision pose d and every pose g, the fewest bounces after
which a robot at d passes g (breadth-first search on the graph whose nodes are the decision poses
plus one node per goal pose, with an edge d → d' per angle and d → g for every pose g that
angle's drive passes; `scipy.sparse.csgraph.shortest_path` with unit weights).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import shortest_path

from bounce_gym.cells.drives import ContactDrives
from bounce_gym.cells.model import CellModel

#: `BounceReach.bounces` of a pose that cannot be passed from a decision pose
UNREACHABLE = -1


class BounceReach:
    """Fewest bounces between the decision poses of a cell model and every pose.

    Args:
        model: the cell model (its bins must hold every angle of ``angles``).
        angles: the bounce angles Φ in radians.

    Attributes:
        decisions: (D,) the decision poses (cell numbers z whose next move is blocked).
        arrival: (N,) for every pose z, the index into ``decisions`` of the pose where a robot
            driving on from z first bumps (z's own index when z is a decision pose).
        bounces: (D, N) int16: the fewest bounces after which a robot at decision pose
            ``decisions[i]`` passes pose z (at least 1), `UNREACHABLE` where it never does.
    """

    def __init__(self, model: CellModel, angles: Sequence[float]) -> None:
        self.model = model
        self.turns = np.array([model.angle_bins(float(a), "bounce angle") % model.n_bins
                               for a in angles], dtype=np.int64)
        n = model.n_cells
        #: where every pose's drive to contact stops (`ContactDrives`, shared with the env)
        self.drives = drives = ContactDrives(model)
        z = np.arange(n, dtype=np.int64)
        #: (N,) the pose one tick of driving leads to, −1 where the next move is blocked
        self.forward = np.where(drives.next != z, drives.next, -1)
        self.decisions = np.flatnonzero(self.forward < 0)
        index = np.full(n, -1, dtype=np.int64)
        index[self.decisions] = np.arange(len(self.decisions))
        self.arrival = index[drives.end]
        self.bounces = self._table()

    def rotated(self, z: np.ndarray, action: np.ndarray) -> np.ndarray:
        """The poses z turned in place by the angles of Φ with indices ``action``."""
        p, k = self.model.decode(np.asarray(z, dtype=np.int64))
        return self.model.cell_id(p, (k + self.turns[np.asarray(action)]) % self.model.n_bins)

    def drive_passes(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every pose passed by drives starting at poses z (each start pose included):
        (index into z, pose) pairs."""
        z = np.asarray(z, dtype=np.int64)
        rows, poses = [np.arange(len(z))], [z]
        live, here = np.arange(len(z)), z
        for _ in range(self.model.n_positions + 1):
            ahead = self.forward[here]
            moving = ahead >= 0
            if not moving.any():
                return np.concatenate(rows), np.concatenate(poses)
            live, here = live[moving], ahead[moving]
            rows.append(live)
            poses.append(here)
        raise AssertionError("a straight drive never reached a wall")

    def _table(self) -> np.ndarray:
        d, n = len(self.decisions), self.model.n_cells
        starts = self.rotated(np.repeat(self.decisions, len(self.turns)),
                              np.tile(np.arange(len(self.turns)), d))
        source = np.repeat(np.arange(d), len(self.turns))
        # decision pose -> next decision pose, for every angle
        nxt = self.arrival[self.drives.end[starts]]
        # decision pose -> goal node (d + pose) for every pose the drive passes
        row, pose = self.drive_passes(starts)
        graph = sp.coo_matrix(
            (np.ones(len(nxt) + len(row)),
             (np.concatenate((source, source[row])), np.concatenate((nxt, d + pose)))),
            shape=(d + n, d + n)).tocsr()
        graph.data[:] = 1.0  # duplicate edges were summed
        dist = shortest_path(graph, directed=True, unweighted=True, indices=np.arange(d))[:, d:]
        out = np.full(dist.shape, UNREACHABLE, dtype=np.int16)
        finite = np.isfinite(dist)
        out[finite] = dist[finite].astype(np.int16)
        return out
