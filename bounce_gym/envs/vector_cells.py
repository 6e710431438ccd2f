"""`CellRobots`: the batched env's robots on the cell backend, each kept as its cell.

On the cell backend a robot that ignores the others is its cell: a position index ``p`` and an
orientation bin ``k`` of the `CellModel`. Every env step of bounce mode starts and ends in
contact, so a step is the rotation of the bounce rule (a new bin) followed by the drive to the
next contact, which `ContactDrives` tabulates per cell. The cell backend takes discrete actions
only, so a whole step is tabulated per (cell, action): where it ends and its ticks.
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
        z, p: (N,) each robot's cell number and its position index.
        turned: (N,) the cell each robot's last bump turned it to, where its drive began.
    """

    def __init__(self, dynamics: BounceDynamics, angles: np.ndarray) -> None:
        self.dynamics = dynamics
        model = self.model = dynamics.backend.model
        self.n = dynamics.n_robots
        drives = ContactDrives(model)
        #: per cell number: the ticks of its drive to contact and the cell where it stops
        self.drive_ticks, self.drive_end = drives.ticks, drives.end
        #: the heading of each bin, as the cell backend snaps headings (bin · width)
        self.bin_heading = np.arange(model.n_bins) * model.bin_width
        direction = np.empty((model.n_bins, 2))  # `RobotState.direction`'s arithmetic
        np.cos(self.bin_heading, out=direction[:, 0])
        np.sin(self.bin_heading, out=direction[:, 1])
        #: the contact normal of a blocked robot of each bin: back along its heading
        self.bin_normal = -direction
        self.n_actions = len(angles)
        z = np.arange(model.n_cells)
        p, k = model.decode(z)
        turns = np.empty((model.n_cells, self.n_actions), dtype=np.int64)
        for action, angle in enumerate(angles.tolist()):
            # the bounce rule, with the angle checked as `BounceDynamics.parameters` checks it
            params = np.full(model.n_bins, dynamics.parameters(angle)[0])
            turned = model.bin_of(dynamics.rule(self.bin_heading, self.bin_normal, params))
            turns[:, action] = model.cell_id(p, turned[k])
        #: per cell z and action a, at z · n_actions + a: the cell the bump turns the robot to
        #: (where the step's drive starts), where the step ends and its drive's ticks
        self.step_turned = turns.ravel()
        self.step_end = drives.end[turns].ravel()
        self.step_ticks = drives.ticks[turns].ravel()
        #: per cell: its position index, centre, bin heading and contact normal
        self.position_of = p
        self.centre_of = model.centres[p]
        self.heading_of = self.bin_heading[k]
        self.normal_of = self.bin_normal[k]
        self.state: RobotState | None = None
        self.z = np.zeros(self.n, dtype=np.int64)
        self.p = np.zeros(self.n, dtype=np.int64)
        self.turned = np.zeros(self.n, dtype=np.int64)

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
        start = self.model.cell_id(p, k)
        ticks = self.drive_ticks[start]
        z = self.z[rows] = self.drive_end[start]
        self.p[rows] = self.position_of[z]
        position, heading = self.centre_of.take(z, axis=0), self.heading_of[z]
        if self.state is None:
            if len(rows) != self.n:
                raise ConfigError("the first reset places every robot")
            self.state = RobotState.at(position, heading)
            # every drive stops where the next cell is blocked, and no contact is an edge's
            # or a robot's: these fields never change
            self.state.blocked[...] = True
            self.state.contact_edge[...] = NO_CONTACT
            self.state.contact_robot[...] = NO_CONTACT
        state = self.state
        state.position[rows] = position
        state.heading[rows] = heading
        state.clock[rows] = ticks
        state.bumps[rows] = 0
        state.contact_normal[rows] = self.normal_of.take(z, axis=0)
        return ticks

    def bounce(self, actions: np.ndarray) -> np.ndarray:
        """One bounce-mode step of every robot (all in contact): the bump tick turns each by
        its action's angle (``actions``: (N,) indices into the angles), then each drives to its
        next contact. Returns the ticks each drove."""
        # ``take`` rather than fancy indexing: the same values, gathered several times faster
        at = self.z * self.n_actions + actions
        self.turned = self.step_turned.take(at)
        ticks = self.step_ticks.take(at)
        z = self.z = self.step_end.take(at)
        self.p = self.position_of.take(z)
        state = self.state
        self.centre_of.take(z, axis=0, out=state.position, mode="clip")  # z is in range
        self.heading_of.take(z, out=state.heading, mode="clip")
        self.normal_of.take(z, axis=0, out=state.contact_normal, mode="clip")
        state.clock[...] = ticks
        state.bumps += 1
        return ticks
