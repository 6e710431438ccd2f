"""State of m robots, stored as arrays (one row per robot)."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

NO_CONTACT = -1


@dataclass
class RobotState:
    """Positions, headings and the sensor-side state of m robots.

    Attributes:
        position: (m, 2) centre of each robot.
        heading: (m,) heading in radians, [0, 2π), 0 = +x, counter-clockwise positive.
        blocked: (m,) phase flag. True = the robot is in contact and faces into what it touches,
            so its next tick is a bump (rotating); False = its next tick drives.
        clock: (m,) ticks since the robot's last bump (the papers' clock).
        bumps: (m,) number of bump ticks so far.
        contact_edge: (m,) world edge the robot touches (valid where blocked), else -1.
        contact_robot: (m,) other robot the robot touches (valid where blocked), else -1.
        contact_normal: (m, 2) unit normal of the touched feature, pointing at the robot.
        odometer: (m,) total distance driven.
        ticks: global clock (ticks since reset).
    """

    position: np.ndarray
    heading: np.ndarray
    blocked: np.ndarray
    clock: np.ndarray
    bumps: np.ndarray
    contact_edge: np.ndarray
    contact_robot: np.ndarray
    contact_normal: np.ndarray
    odometer: np.ndarray
    ticks: int = 0

    @classmethod
    def at(cls, position: np.ndarray, heading: np.ndarray) -> RobotState:
        """A fresh state (nothing touched yet) at the given poses."""
        position = np.array(position, dtype=np.float64).reshape(-1, 2)
        m = len(position)
        heading = np.mod(np.array(heading, dtype=np.float64).reshape(m), 2 * np.pi)
        return cls(
            position=position,
            heading=heading,
            blocked=np.zeros(m, dtype=bool),
            clock=np.zeros(m, dtype=np.int64),
            bumps=np.zeros(m, dtype=np.int64),
            contact_edge=np.full(m, NO_CONTACT, dtype=np.int64),
            contact_robot=np.full(m, NO_CONTACT, dtype=np.int64),
            contact_normal=np.zeros((m, 2)),
            odometer=np.zeros(m),
        )

    @property
    def n_robots(self) -> int:
        return len(self.heading)

    @property
    def direction(self) -> np.ndarray:
        """(m, 2) unit heading vectors."""
        out = np.empty((len(self.heading), 2))
        np.cos(self.heading, out=out[:, 0])
        np.sin(self.heading, out=out[:, 1])
        return out

    def copy(self) -> RobotState:
        return RobotState(
            **{f.name: (getattr(self, f.name).copy() if f.name != "ticks" else self.ticks)
               for f in fields(self)}
        )
