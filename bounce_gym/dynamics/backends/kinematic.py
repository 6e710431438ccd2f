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

from bounce_gym.dynamics.backends.base import MotionBackend, pair_contact_times
from bounce_gym.dynamics.state import NO_CONTACT, RobotState
from bounce_gym.errors import ConfigError

#: Consecutive zero-length events after which the integrator declares itself stuck (a bug).
_MAX_ZENO = 10_000


class KinematicBackend(MotionBackend):
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

    def update_contacts(self, state: RobotState, robots: np.ndarray) -> None:
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

    def drive(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        # Internally time is measured as distance driven (one tick = step_length), so a robot
        # that stops at a wall lands exactly at position + direction * (its wall distance).
        if until_first_block and state.blocked.any():
            return 0
        self._check_drive_window(max_ticks, until_first_block)
        tol = self.contact_tol
        limit = float(max_ticks) * self.step_length
        driven = np.zeros(state.n_robots)
        elapsed, zeno = 0.0, 0
        while elapsed < limit - tol:
            moving = np.flatnonzero(~state.blocked)
            if len(moving) == 0:
                break
            dirs = state.direction[moving]
            s_wall = self._ahead_distance[moving]
            s_robot = np.full(len(moving), np.inf)
            if self.collide:
                velocity = np.zeros_like(state.position)
                velocity[moving] = dirs
                s_robot = pair_contact_times(state.position, velocity, self.radius, moving).min(axis=1)
            if not np.isfinite(s_wall).all():
                lost = int(moving[~np.isfinite(s_wall)][0])
                raise RuntimeError(f"robot {lost} left the free space at {state.position[lost]}")
            s_next = float(min(s_wall.min(), s_robot.min()))
            ds = min(s_next, limit - elapsed)
            travel = np.minimum(s_wall, ds)  # the robot meeting its wall travels exactly s_wall
            state.position[moving] += dirs * travel[:, None]
            self._ahead_distance[moving] = s_wall - travel
            driven[moving] += travel
            elapsed += ds
            if s_next > ds + tol:
                break  # the window closed before the next contact
            zeno = zeno + 1 if ds <= tol else 0
            if zeno > _MAX_ZENO:
                raise RuntimeError("kinematic integrator made no progress (contact bookkeeping bug)")
            walls = moving[s_wall <= s_next + tol]
            self._block_at_walls(state, walls, self._ahead_edge[walls], self._ahead_normal[walls])
            if self.collide and np.any(s_robot <= s_next + tol):
                self._stop_touching(state, moving[s_robot <= s_next + tol])
            if until_first_block:
                limit = min(limit, self._end_of_tick(elapsed))
        return self._finish_drive(state, driven, limit, elapsed)

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
