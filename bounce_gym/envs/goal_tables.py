"""`GoalTables`: the navigation task's goal test and progress potential as lookups on cells.

On the cell backend a bounce-mode step of a lone robot ends with a drive from the cell its bump
turned it to (the *turned* cell) to its next contact, and a random goal is a cell (its centre
and bin heading). Whether that drive enters the goal region, and after how many ticks, then
depends only on the turned cell and the goal's position index, and the heading half of the test
only on the two bins; Φ of the ``progress`` reward depends only on the goal's grid node and the
robot's position index. `GoalTables` keeps these as flat arrays, one column per goal, so that a
batch of N envs tests arrival and reads Φ with a few gathers instead of a test per env.

A goal's column is filled the first time an episode draws that goal, with the single-robot
task's own tests (`NavigationTask.ticks_to_goal` on each drive that passes near the goal,
`NavigationTask.goal_potentials`), so the batch agrees with the single env to the last bit. The
arrays take ``n_positions`` × (``n_cells`` + ``n_nodes``) entries at most; `GoalTables.fits`
says whether a model's stay within `MAX_ENTRIES` (larger maps keep the per-env tests).
"""

from __future__ import annotations

import numpy as np

from bounce_gym.envs.tasks import NavigationTask
from bounce_gym.envs.tasks.base import StepEvents
from bounce_gym.envs.vector_cells import CellRobots

#: the most entries the arrival and the potential tables may hold together (128 MiB of int32
#: and float64 at most)
MAX_ENTRIES = 1 << 24
#: an arrival entry not computed yet; -1 is a drive that never enters the goal region
UNKNOWN = -2
#: the margin `passes_near` adds to the goal radius: far above rounding, so its screen never
#: drops a segment the exact test accepts
NEAR_MARGIN = 1e-6


class GoalTables:
    """Arrival and Φ lookups of ``task`` (on the cell backend) for the drives of ``robots``.

    Attributes:
        off_cell: the goal position index of a goal that is not a cell (n_positions), whose
            arrival column is -1 throughout.
        arrival: at goal position gp × n_cells + turned cell z: the drive ticks after which the
            drive from z enters the region of a goal at position gp (0: it starts inside),
            -1 if it never does, `UNKNOWN` until gp's column is filled (`fill`).
        aligned: at drive bin k × n_bins + goal bin: whether the heading test passes.
        potential: at goal node × n_positions + position index: Φ (``progress`` reward only,
            else None), filled per goal node (`fill`).
    """

    @staticmethod
    def fits(robots: CellRobots, task: NavigationTask) -> bool:
        """Whether the tables of this model and task stay within `MAX_ENTRIES`."""
        model = robots.model
        nodes = task.geodesic.n_nodes if task.geodesic is not None else 0
        return model.n_positions * (model.n_cells + nodes) <= MAX_ENTRIES

    def __init__(self, robots: CellRobots, task: NavigationTask) -> None:
        model = robots.model
        self.task = task
        self.n_positions, self.n_cells, self.n_bins = model.n_positions, model.n_cells, model.n_bins
        self.centres, self.bin_width = model.centres, model.bin_width
        #: per cell z: the drive from z — its start and end points, heading and ticks
        self.drive_start = robots.centre_of
        self.drive_end = robots.centre_of.take(robots.drive_end, axis=0)
        self.drive_heading = robots.heading_of
        self.drive_ticks = robots.drive_ticks
        self.off_cell = self.n_positions
        self.arrival = np.full((self.n_positions + 1) * self.n_cells, UNKNOWN, dtype=np.int32)
        self.arrival[self.off_cell * self.n_cells:] = -1
        self.filled = np.zeros(self.n_positions + 1, dtype=bool)  # per goal position
        self.filled[self.off_cell] = True
        self.complete = self.potential_complete = False  # every column filled
        goal_headings = np.arange(self.n_bins) * self.bin_width  # as the draws place goals
        self.aligned = task.heading_within(robots.bin_heading[:, None],
                                           goal_headings[None, :]).ravel()
        self.node_of_position = None
        self.potential = None
        if task.geodesic is not None:
            self.node_of_position = task.geodesic.node_of(model.centres)
            self.potential = np.zeros(task.geodesic.n_nodes * self.n_positions)
            self.has_potential = np.zeros(task.geodesic.n_nodes, dtype=bool)

    def goal_cell(self, position: np.ndarray, heading: float) -> tuple[int, int]:
        """(position index, bin) of a goal at ``position`` (2,) with ``heading`` where that goal
        is a cell (its centre exactly, a bin's heading exactly), else (`off_cell`, -1)."""
        p = int(np.argmin(np.abs(self.centres - position).sum(axis=1)))
        k = round(heading / self.bin_width)
        on_cell = np.array_equal(self.centres[p], position)
        if on_cell and 0 <= k < self.n_bins and k * self.bin_width == heading:
            return p, k
        return self.off_cell, -1

    def fill(self, goal_positions: np.ndarray, goal_nodes: np.ndarray | None) -> None:
        """Fill the arrival columns of goal position indices ``goal_positions`` and the Φ
        columns of grid nodes ``goal_nodes`` not filled yet."""
        cells = self.n_cells
        if not self.complete:
            for gp in set(goal_positions[~self.filled.take(goal_positions)].tolist()):
                self.arrival[gp * cells:(gp + 1) * cells] = self._arrivals(gp)
                self.filled[gp] = True
            self.complete = bool(self.filled.all())
        if self.potential is None or self.node_of_position is None or goal_nodes is None \
                or self.potential_complete:
            return
        n = self.n_positions
        for node in set(goal_nodes[~self.has_potential.take(goal_nodes)].tolist()):
            self.potential[node * n:(node + 1) * n] = self.task.goal_potentials(node).take(
                self.node_of_position)
            self.has_potential[node] = True
        self.potential_complete = bool(self.has_potential.all())

    def _arrivals(self, gp: int) -> np.ndarray:
        """The arrival column of a goal at position index ``gp``: the task's exact test on the
        drives that pass near the goal (a superset of those it accepts), -1 elsewhere."""
        column = np.full(self.n_cells, -1, dtype=np.int32)
        goal = self.centres[gp:gp + 1]
        near = np.flatnonzero(passes_near(self.drive_start, self.drive_end, goal[0],
                                          self.task.goal_radius + NEAR_MARGIN))
        for z in near.tolist():
            heading = self.drive_heading[z:z + 1]
            # a drive without its bump, towards a goal with the drive's own heading: what is
            # left of the test is where the drive enters the goal region
            drive = StepEvents(ticks=int(self.drive_ticks[z]), start=self.drive_start[z:z + 1],
                               end=self.drive_end[z:z + 1], heading=heading,
                               bumps=np.zeros(1, dtype=np.int64), angles=np.full(1, np.nan),
                               angle_changed=np.zeros(1, dtype=bool),
                               robot_contact=np.zeros(1, dtype=bool))
            ticks = self.task.ticks_to_goal(drive, (goal, heading))
            if ticks is not None:
                column[z] = int(ticks)
        return column


def passes_near(start: np.ndarray, end: np.ndarray, point: np.ndarray,
                radius: float) -> np.ndarray:
    """(m,) bool: the segments ``start`` → ``end`` ((m, 2) each) pass within ``radius`` of
    ``point`` ((2,), or one per segment (m, 2)): with ``radius`` the goal radius plus
    `NEAR_MARGIN`, a superset of the segments the exact test of `NavigationTask.ticks_to_goal`
    accepts."""
    sx, sy = (end - start).T
    rx, ry = (point - start).T
    length2 = sx * sx + sy * sy
    along = np.clip((rx * sx + ry * sy) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    gx, gy = rx - along * sx, ry - along * sy
    return gx * gx + gy * gy <= radius * radius
