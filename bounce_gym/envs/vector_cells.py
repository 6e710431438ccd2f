"""`CellRobots`: the batched env's robots on the cell backend, each kept as its cell.

On the cell backend a robot that ignores the others is its cell: a position index ``p`` and an
orientation bin ``k`` of the `CellModel`. Every env step of bounce mode starts and ends in
contact, so a step is the rotation of the bounce rule (a new bin) followed by the drive to the
next contact, which `ContactDrives` tabulates per cell. The cell backend takes discrete actions
only, so the rotations are tabulated too (bin x action): the whole step is a few array lookups.
The float pose of each robot (the cell centre and the bin heading, the values the cell backend
gives a lone robot) is written into a `RobotState` for the observations, infos and tasks.

That state keeps every field a lone robot's state has except the odometer (no observation,
reward or info of the batched env reads it): it stays 0.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.drives import ContactDrives
from bounce_gym.dynamics import BounceDynamics, RobotState
from bounce_gym.dynamics.state import NO_CONTACT
from bounce_gym.errors import ConfigError


class CellRobots:
    """N robots of ``dynamics`` (cell backend, robots ignoring each other) stepped as cells.

    ``angles``: the bounce angles (radians) of the discrete actions.

    Attributes:
        model: the `CellModel`.
        state: the robots' `RobotState` (None before the first `place`).
        p, k: (N,) each robot's position index and bin.
    """

    def __init__(self, dynamics: BounceDynamics, angles: np.ndarray) -> None:
        self.dynamics = dynamics
        model = self.model = dynamics.backend.model
        self.n = dynamics.n_robots
        drives = ContactDrives(model)
        self.drive_ticks = drives.ticks  # per cell number
        self.drive_end = model.decode(drives.end)[0]  # position index where each drive stops
        #: the heading of each bin, as the cell backend snaps headings (bin · width)
        self.bin_heading = np.arange(model.n_bins) * model.bin_width
        direction = np.empty((model.n_bins, 2))  # `RobotState.direction`'s arithmetic
        np.cos(self.bin_heading, out=direction[:, 0])
        np.sin(self.bin_heading, out=direction[:, 1])
        #: the contact normal of a blocked robot of each bin: back along its heading
        self.bin_normal = -direction
        #: (n_bins, n_actions) the bin a robot in each bin turns to under each action's angle:
        #: the bounce rule (with the angle checked as `BounceDynamics.parameters` checks it)
        self.turns = np.empty((model.n_bins, len(angles)), dtype=np.int64)
        for action, angle in enumerate(angles.tolist()):
            params = np.full(model.n_bins, dynamics.parameters(angle)[0])
            self.turns[:, action] = model.bin_of(dynamics.rule(self.bin_heading, self.bin_normal,
                                                               params))
        self.state: RobotState | None = None
        self.p = np.zeros(self.n, dtype=np.int64)
        self.k = np.zeros(self.n, dtype=np.int64)

    def cells_of(self, position: np.ndarray, heading: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position index, bin) of start poses, as the cell backend places them;
        `ConfigError` for a position outside the model's free cells."""
        z = self.model.cell_of(position, heading)
        if np.any(z < 0):
            bad = int(np.flatnonzero(z < 0)[0])
            raise ConfigError(f"start position {np.asarray(position)[bad].tolist()} is not in a "
                              "free cell of the cell model")
        return self.model.decode(z)

    def place(self, rows: np.ndarray, p: np.ndarray, k: np.ndarray) -> np.ndarray:
        """Start robots ``rows`` afresh in cells (``p``, ``k``) and drive each to its first
        contact (the first call places every robot). Returns the ticks each drove."""
        ticks = self.drive_ticks[self.model.cell_id(p, k)]
        end = self.drive_end[self.model.cell_id(p, k)]
        self.p[rows] = end
        self.k[rows] = k
        position, heading = self.model.centres[end], self.bin_heading[k]
        if self.state is None:
            if len(rows) != self.n:
                raise ConfigError("the first reset places every robot")
            self.state = RobotState.at(position, heading)
        state = self.state
        state.position[rows] = position
        state.heading[rows] = heading
        state.blocked[rows] = True  # a drive stops where the next cell is blocked
        state.clock[rows] = ticks
        state.bumps[rows] = 0
        state.contact_edge[rows] = NO_CONTACT
        state.contact_robot[rows] = NO_CONTACT
        state.contact_normal[rows] = self.bin_normal[k]
        return ticks

    def bounce(self, actions: np.ndarray) -> np.ndarray:
        """One bounce-mode step of every robot (all in contact): the bump tick turns each by
        its action's angle (``actions``: (N,) indices into the angles), then each drives to its
        next contact. Returns the ticks each drove."""
        k = self.k = self.turns[self.k, actions]
        z = self.model.cell_id(self.p, k)
        ticks = self.drive_ticks[z]
        p = self.p = self.drive_end[z]
        state = self.state
        state.position[...] = self.model.centres[p]
        state.heading[...] = self.bin_heading[k]
        state.clock[...] = ticks
        state.bumps += 1
        state.contact_normal[...] = self.bin_normal[k]
        return ticks
