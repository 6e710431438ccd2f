"""Exact event-driven motion: jump straight to the next contact.

Between contacts every robot moves in a straight line at ``step_length`` per tick, so the next
event is found in closed form — the first wall contact of each robot by `World.first_hit` (a swept
disk, exact for any radius) and the first disk–disk contact of each pair by solving
|Δp + Δv t| = 2R. All robots advance to the earliest event, the robots involved stop, and the loop
continues. Vectorised over robots, no time stepping.

A robot's first wall contact along its ray does not change while it drives along that ray, so it
is cast once per heading change (in `update_contacts`) and kept as the *wall ahead*; driving only
shortens the remaining distance. A bounce therefore costs one ray cast.
"""

from __future__ import annotations

import math

import numpy as np

from bounce_gym.dynamics.backends.base import EventDrivenBackend
from bounce_gym.dynamics.state import NO_CONTACT, RobotState
from bounce_gym.errors import ConfigError
from bounce_gym.worlds.raycast import first_hit_scalar


class KinematicBackend(EventDrivenBackend):
    """Analytic ray-cast backend: the ground truth the other backends are checked against."""

    name = "kinematic"
    drives_independently = True

    def reset(self, state: RobotState) -> None:
        self.check_start(state)
        m = state.n_robots
        self._ahead_distance = np.zeros(m)
        self._ahead_edge = np.full(m, NO_CONTACT, dtype=np.int64)
        self._ahead_normal = np.zeros((m, 2))
        self.update_contacts(state, np.arange(m))

    def place(self, state: RobotState, robots: np.ndarray) -> None:
        """Take over robots ``robots`` of ``state``, just placed, while the others keep driving
        (robots that ignore each other; `reset` places every robot): check their starts
        (`ConfigError`) and cast their walls ahead."""
        if self.collide:
            raise ConfigError("placing some robots among others needs robot_collisions='ignore'")
        self.check_start(RobotState.at(state.position[robots], state.heading[robots]))
        self.update_contacts(state, robots)

    def update_contacts(self, state: RobotState, robots: np.ndarray) -> None:
        if state.n_robots == 1 and len(robots) == 1:
            self._update_one(state)
            return
        robots = np.asarray(robots, dtype=np.int64)
        if len(robots) == 0:
            return
        # all robots (e.g. a lone robot): a basic slice is cheaper than fancy indexing
        sel = slice(None) if len(robots) == state.n_robots else robots
        hits = self.world.first_hit(state.position[sel], state.direction[sel], self.radius)
        self._ahead_distance[sel] = hits.distance
        self._ahead_edge[sel] = hits.edge
        self._ahead_normal[sel] = hits.normal
        self._classify_contacts(state, robots, sel, hits.distance, hits.edge, hits.normal)

    def _update_one(self, state: RobotState) -> None:
        """`update_contacts` of a lone robot in plain floats (no robot can block it)."""
        (dx, dy), = state.direction.tolist()  # numpy's cos and sin, as for many robots
        x, y = state.position[0].tolist()
        dist, edge, _, nx, ny = first_hit_scalar(self.world, x, y, dx, dy, self.radius)
        self._ahead_distance[0] = dist
        self._ahead_edge[0] = edge
        self._ahead_normal[0] = nx, ny
        wall = dist <= self.contact_tol
        state.contact_edge[0] = edge if wall else NO_CONTACT
        state.contact_normal[0] = nx, ny
        state.blocked[0] = wall

    # Time is distance driven (one tick = step_length), so a robot that stops at a wall lands
    # exactly at position + direction * (its wall distance).
    def _wall_distances(self, state: RobotState, robots: np.ndarray) -> np.ndarray:
        return self._ahead_distance[robots]

    def _advance(self, state, moving, s_wall, ds, event):
        travel = np.minimum(s_wall, ds)  # the robot meeting its wall travels exactly s_wall
        state.position[moving] += state.direction[moving] * travel[:, None]
        self._ahead_distance[moving] = s_wall - travel
        return travel

    def _settle_contacts(self, state, walls, robots, pairs):
        self._block_at_walls(state, walls, self._ahead_edge[walls], self._ahead_normal[walls])
        if len(robots):
            self._stop_touching(state, robots)

    def drive_each(self, state: RobotState) -> np.ndarray:
        """Drive every unblocked robot to its own next contact, independently of the others.

        Only meaningful when robots ignore each other: each robot's path then does not depend on
        when the others move, so no common clock is needed and ``state.ticks`` is left alone.
        For a single robot this equals ``drive(inf, until_first_block=True)`` (and does advance
        ``state.ticks``), computed with scalars because it is the hot path of single-robot envs.
        Returns the ticks each robot drove.
        """
        if self.collide:
            raise ConfigError("independent driving needs robot_collisions='ignore'")
        if state.n_robots == 1:
            return np.array([self._drive_one(state)], dtype=np.int64)
        moving = np.flatnonzero(~state.blocked)
        ticks = np.zeros(state.n_robots, dtype=np.int64)
        if len(moving) == 0:
            return ticks
        dist = self._ahead_distance[moving]
        state.position[moving] += state.direction[moving] * dist[:, None]
        state.odometer[moving] += dist
        self._ahead_distance[moving] = 0.0
        state.blocked[moving] = True
        state.contact_edge[moving] = self._ahead_edge[moving]
        state.contact_robot[moving] = NO_CONTACT
        state.contact_normal[moving] = self._ahead_normal[moving]
        ticks[moving] = np.ceil(dist / self.step_length - self.time_tol).astype(np.int64)
        state.clock[moving] += ticks[moving]
        return ticks

    def _drive_one(self, state: RobotState) -> int:
        if state.blocked[0]:
            return 0
        dist = float(self._ahead_distance[0])
        heading = float(state.heading[0])
        pos = state.position[0]
        direction = np.array([math.cos(heading), math.sin(heading)])
        pos += direction * dist
        self._ahead_distance[0] = 0.0
        state.odometer[0] += dist
        state.blocked[0] = True
        state.contact_edge[0] = self._ahead_edge[0]
        state.contact_robot[0] = NO_CONTACT
        state.contact_normal[0] = self._ahead_normal[0]
        ticks = math.ceil(dist / self.step_length - self.time_tol)
        state.clock[0] += ticks
        state.ticks += ticks
        return ticks
