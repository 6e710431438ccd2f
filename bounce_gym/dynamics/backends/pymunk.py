"""Physics-engine motion: robots are pymunk bodies, walls are static segments.

The backend builds one `pymunk.Space` (on the first `reset`, and again after unpickling) holding

* the **walls**: one static `pymunk.Segment` (radius 0) per world edge, all rings;
* the **robots**: dynamic bodies (mass 1, infinite moment, no gravity, no damping) carrying a
  `pymunk.Circle` of radius ``radius + skin``;
* the **configuration-space boundary**, used only by queries: every edge shifted by ``radius``
  along its inward normal and a circle of radius ``radius`` about every reflex vertex (disk robots
  only), all padded by ``pad`` (see below). Their category collides with nothing.

Driving is **conservative advancement**. For every robot that moves, a pymunk segment query along
its heading finds the first boundary feature it can reach; for robot pairs the closed form of
`pair_contacts` gives the first disk–disk contact. The space is then stepped with ``dt`` equal
to the earliest of these events (capped by the drive window) — one physics step per event, so a
single-robot bounce costs one step however long the drive — and pymunk itself moves the bodies.
Engine time is distance: robots move at unit speed, one tick lasts ``step_length`` time units of
the space, and a step moves a body to exactly ``p + heading * dt`` (Chipmunk's integrator with no
forces, damping 1 and unprocessed collisions). No robot can tunnel: a step never goes past the
first reachable feature of any robot.

The **bump sensor is the engine's contact callback**. A ``pre_solve`` handler on the robot–wall
(and, with ``robot_collisions='bounce'``, robot–robot) collision types records which shapes touch
in the step that ends at an event, and sets ``arbiter.process_collision = False`` so the solver
never pushes robots: they stop exactly where they touch. ``pre_solve`` runs in every step in which
two shapes overlap (level-triggered); ``begin`` fires only on the first overlap and would miss a
contact whose shapes already overlapped within the skin. A robot is blocked when the engine
reports the contact and the robot faces what it touches (the query's approach test for walls,
`MotionBackend.robot_blockers` for robots). A predicted contact that the engine does not report
raises `RuntimeError` instead of being trusted. Robots standing still stop sensing walls (their
shape filter drops the wall category) so that resting robots cost no callbacks; they keep sensing
robots that run into them.

Model details (the tests pin the agreement with the kinematic backend):

* **Skin.** Robot shapes are ``skin = 1e-6 x world diameter`` larger than the robot, so the engine
  reports a contact when the robot is *exactly* touching: no overshoot and no putting back are
  needed, and a robot never overlaps a wall by more than rounding. Point robots (``radius = 0``)
  carry a circle of radius ``skin`` in the engine, but their contacts, positions and normals are
  those of the point model.
* **Why padded C-space shapes and not ``segment_query(…, radius, …)`` against the walls.**
  (1) pymunk culls shapes by the *centre line* of a query in its bounding-box tree, so a disk
  whose centre passes beside a hole's corner is not reported and would tunnel through it;
  (2) a query reports every shape within its radius of the start (alpha 0) whatever the
  direction, so ``segment_query_first`` would return the wall the robot is leaving; (3) Chipmunk's
  ray–circle test loses about sqrt(machine epsilon) x query length, so hair-thin shapes are missed
  by rays that graze a vertex. Hence rays (radius 0) against the configuration-space boundary,
  padded by ``pad = 1e-6 x diameter``: pymunk returns every candidate feature the ray comes near
  (all hits, not just the first), and the exact contact distance, the approach test and the
  tie-breaking are then computed from the feature's geometry exactly as
  `bounce_gym.worlds.raycast.first_hit` does, which removes the padding again.
* The first reachable wall of a robot does not change while it drives straight, so the query
  result is cached per robot (keyed by exact position and heading) and only redone after a
  rotation, or when the state was changed from outside.
* A lone robot (the single-robot env's hot path) takes the same query, step and callback with
  its bookkeeping in plain floats (`EventDrivenBackend` gives it at most one event per drive).

**One Space per backend, not per episode.** pymunk bodies, shapes and handlers form reference
cycles, so a Space dropped at every reset waits for Python's cyclic garbage collector (about
300 kB of Chipmunk memory per reset; 2,000 resets held 635 MB with the collector paused). The
walls and query shapes never change, and nothing else carries over between episodes: `reset`
rewrites every body's position and velocity before the next step and clears the touch record,
the handlers are installed once, and the engine's arbiter cache cannot influence anything because
collisions are never processed and ``pre_solve`` reports only current overlaps. A reused Space
and a new one therefore give bit-identical episodes (tested).

Pickling drops the `Space`; the engine objects are rebuilt on demand from the world and the robot
state. This is exact: the space holds nothing the state and the cache do not — positions and
velocities are written from the state before stepping, collisions are never processed (so the
engine's cached impulses and arbiter history cannot move anything), and every decision taken from
callbacks and query results is independent of the order in which pymunk reports them.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from bounce_gym.dynamics.backends.base import EventDrivenBackend
from bounce_gym.dynamics.state import NO_CONTACT, RobotState
from bounce_gym.errors import ConfigError
from bounce_gym.worlds.raycast import GRAZE

#: Robot shapes are this much (times the world diameter) larger than the robot: the contact skin.
SKIN_REL = 1e-6
#: Query shapes are padded by this much (times the world diameter). Chipmunk's ray–circle test
#: loses about sqrt(machine epsilon) x query length, so much thinner shapes (``world.tol``) are
#: missed by rays that graze a vertex: the pad must be well above 1e-8 x diameter.
PAD_REL = 1e-6
#: Step length used when an event is due immediately (pymunk ignores ``step(0)``): moves nothing.
_SENSE_DT = 1e-300
#: Smallest approach speed (unit heading against unit normal) counted as facing a wall, as in
#: `bounce_gym.worlds.raycast`.
_APPROACH = 1e-12

_ROBOT_TYPE, _WALL_TYPE = 1, 2
_CAT_WALL, _CAT_ROBOT, _CAT_CSPACE, _CAT_QUERY = 0x1, 0x2, 0x4, 0x8
_EDGE, _VERTEX = 0, 1


class PymunkBackend(EventDrivenBackend):
    """pymunk 7 backend: static segment walls, disk robots, contact callbacks as bump sensor."""

    name = "pymunk"

    def __init__(self, world, n_robots, radius, step_length, robot_collisions) -> None:
        super().__init__(world, n_robots, radius, step_length, robot_collisions)
        self.skin = SKIN_REL * world.diameter
        #: thickness of the configuration-space query shapes (candidates only, see module doc)
        self.pad = PAD_REL * world.diameter
        #: distance at or below which a robot counts as touching what is ahead of it
        #: longest straight drive inside the world (bounding-box diagonal, with margin)
        self._horizon = 1.01 * world.diameter + 100.0 * world.tol
        r = self.radius
        normals = world.normals
        shifted = world.edge_start + r * normals
        vec = world.edge_end - world.edge_start
        # per edge: shifted start, edge vector, length and the parameter tolerance (plain floats:
        # the per-hit arithmetic runs in Python)
        self._edge_geom = [
            (float(a[0]), float(a[1]), float(e[0]), float(e[1]), float(length),
             float(world.tol / length))
            for a, e, length in zip(shifted, vec, world.lengths, strict=True)
        ]
        self._normal_xy = [(float(n[0]), float(n[1])) for n in normals]
        self._vertex_xy = [(float(p[0]), float(p[1])) for p in world.edge_start]
        self._reflex = np.flatnonzero(world.reflex) if r > 0 else np.empty(0, dtype=np.int64)
        # previous edge in the same ring: a vertex contact touches edge v and edge prev[v]
        prev = np.arange(world.n_edges) - 1
        for ring in np.unique(world.edge_ring):
            idx = np.flatnonzero(world.edge_ring == ring)
            prev[idx[0]] = idx[-1]
        self._prev_edge = prev
        m = self.n_robots
        # cached first wall hit of each robot along its heading, measured from ``_hit_origin``
        self._hit_origin = np.full((m, 2), np.nan)
        self._hit_heading = np.full(m, np.nan)
        self._hit_dist = np.full(m, np.inf)
        self._hit_edge = np.full(m, NO_CONTACT, dtype=np.int64)
        self._hit_vertex = np.full(m, NO_CONTACT, dtype=np.int64)
        self._hit_normal = np.zeros((m, 2))
        self._drop_engine()

    # -- engine objects ---------------------------------------------------------------------
    def _drop_engine(self) -> None:
        self._space: pymunk.Space | None = None
        self._bodies: list[pymunk.Body] = []
        self._disks: list[pymunk.Circle] = []
        self._robot_of: dict[pymunk.Shape, int] = {}
        self._edge_of: dict[pymunk.Shape, int] = {}
        self._feature_of: dict[pymunk.Shape, tuple[int, int]] = {}
        self._forget_engine_state()

    def _forget_engine_state(self) -> None:
        """Forget what the bodies hold and what touched, so the next step rewrites everything."""
        self._touching: list[tuple[pymunk.Shape, pymunk.Shape]] = []
        self._armed = False
        #: what the engine bodies currently hold (NaN = unknown, write before the next step)
        self._body_pos = np.full((self.n_robots, 2), np.nan)
        self._body_vel = np.full((self.n_robots, 2), np.nan)
        self._body_senses_walls = np.ones(self.n_robots, dtype=bool)
        for disk in self._disks:  # match the record above (a reused Space keeps its shapes)
            disk.filter = self._filters[True]

    def _build_space(self) -> None:
        """A fresh space: walls, configuration-space query shapes, robot bodies, handlers."""
        self._drop_engine()
        world, r = self.world, self.radius
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 1.0
        static = space.static_body
        wall_filter = pymunk.ShapeFilter(categories=_CAT_WALL, mask=_CAT_ROBOT)
        cspace_filter = pymunk.ShapeFilter(categories=_CAT_CSPACE, mask=_CAT_QUERY)
        shapes: list[pymunk.Shape] = []
        for k, (a, b) in enumerate(zip(world.edge_start, world.edge_end, strict=True)):
            wall = pymunk.Segment(
                static, (float(a[0]), float(a[1])), (float(b[0]), float(b[1])), 0.0
            )
            wall.collision_type = _WALL_TYPE
            wall.filter = wall_filter
            self._edge_of[wall] = k
            n = world.normals[k]
            sa, sb = a + r * n, b + r * n
            line = pymunk.Segment(
                static, (float(sa[0]), float(sa[1])), (float(sb[0]), float(sb[1])), self.pad
            )
            line.filter = cspace_filter
            self._feature_of[line] = (_EDGE, k)
            shapes += [wall, line]
        for v in self._reflex.tolist():
            p = world.edge_start[v]
            circle = pymunk.Circle(static, r + self.pad, (float(p[0]), float(p[1])))
            circle.filter = cspace_filter
            self._feature_of[circle] = (_VERTEX, v)
            shapes.append(circle)
        # a robot standing still need not feel the wall it rests on (that would only cost a
        # callback per step); it keeps feeling robots that run into it
        others = _CAT_ROBOT if self.collide else 0
        self._filters = (
            pymunk.ShapeFilter(categories=_CAT_ROBOT, mask=others),
            pymunk.ShapeFilter(categories=_CAT_ROBOT, mask=_CAT_WALL | others),
        )
        for i in range(self.n_robots):
            body = pymunk.Body(1.0, math.inf)
            disk = pymunk.Circle(body, r + self.skin)
            disk.collision_type = _ROBOT_TYPE
            disk.filter = self._filters[True]
            self._bodies.append(body)
            self._disks.append(disk)
            self._robot_of[disk] = i
            shapes += [body, disk]
        space.add(*shapes)
        space.on_collision(_ROBOT_TYPE, _WALL_TYPE, pre_solve=self._on_touch)
        if self.collide:
            space.on_collision(_ROBOT_TYPE, _ROBOT_TYPE, pre_solve=self._on_touch)
        self._space = space
        self._query_filter = pymunk.ShapeFilter(categories=_CAT_QUERY, mask=_CAT_CSPACE)

    def _on_touch(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        """The bump sensor: record touching shapes; never let the solver respond."""
        arbiter.process_collision = False
        if self._armed:
            self._touching.append(arbiter.shapes)

    def _engine(self) -> pymunk.Space:
        if self._space is None:
            self._build_space()
        return self._space

    def _write_bodies(self, state: RobotState, velocity: np.ndarray) -> None:
        """Make the engine bodies hold the state's velocities, and its positions before the first
        step of a drive (the state may have been changed from outside since the last)."""
        positions, self._synced = not self._synced, True
        bodies = self._bodies
        moving = ~state.blocked
        for i in np.flatnonzero(moving != self._body_senses_walls).tolist():
            self._disks[i].filter = self._filters[bool(moving[i])]
        self._body_senses_walls[:] = moving
        if positions:
            stale = np.flatnonzero(np.any(state.position != self._body_pos, axis=1))
            for i in stale.tolist():
                bodies[i].position = (float(state.position[i, 0]), float(state.position[i, 1]))
            self._body_pos[stale] = state.position[stale]
        stale = np.flatnonzero(np.any(velocity != self._body_vel, axis=1))
        for i in stale.tolist():
            bodies[i].velocity = (float(velocity[i, 0]), float(velocity[i, 1]))
        self._body_vel[stale] = velocity[stale]

    def _write_lone_body(self, state: RobotState, velocity: list[float]) -> None:
        """`_write_bodies` of a lone robot, in plain floats. It is written only to drive, so its
        shape keeps sensing walls (the filter every robot gets on `reset`)."""
        positions, self._synced = not self._synced, True
        body = self._bodies[0]
        if positions:
            position = state.position[0].tolist()
            if position != self._body_pos[0].tolist():  # NaN (unknown) is unequal to anything
                body.position = tuple(position)
                self._body_pos[0] = position
        if velocity != self._body_vel[0].tolist():
            body.velocity = tuple(velocity)
            self._body_vel[0] = velocity

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        for key in ("_space", "_bodies", "_disks", "_filters", "_robot_of", "_edge_of",
                    "_feature_of", "_touching", "_query_filter", "_body_pos", "_body_vel",
                    "_body_senses_walls", "_armed"):
            state.pop(key, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._drop_engine()

    # -- queries ----------------------------------------------------------------------------
    def _cast(self, px: float, py: float, dx: float, dy: float):
        """First configuration-space feature the robot at (px, py) reaches along (dx, dy).

        Returns ``(distance, edge, vertex, nx, ny)``; distance ``inf`` if nothing is reached.
        pymunk finds the candidate features (every query shape the ray meets, including those it
        starts in); their exact distance, the approach test and the tie-breaking are those of
        `bounce_gym.worlds.raycast.first_hit`: only approaching contacts count, and an origin up
        to ``world.tol`` behind a shifted edge (or inside a vertex circle) touches it at once.
        pymunk may report extra candidates (the query shapes are padded); they fail these tests.
        """
        h = self._horizon
        hits = self._space.segment_query(
            (px, py), (px + dx * h, py + dy * h), 0.0, self._query_filter
        )
        tol = self.world.tol
        best_e, edge = math.inf, NO_CONTACT
        best_v, vertex = math.inf, NO_CONTACT
        geom = self._edge_geom
        feature_of = self._feature_of
        for hit in hits:
            kind, k = feature_of[hit.shape]
            if kind == _EDGE:
                ax, ay, ex, ey, length, utol = geom[k]
                den = dx * ey - dy * ex  # cross(d, e) = |e| x approach speed
                if den < _APPROACH * length:
                    continue  # moving along or away from this edge
                wx, wy = ax - px, ay - py
                num_t = wx * ey - wy * ex
                if num_t < -tol * length:
                    continue  # more than tol behind the shifted edge
                num_u = wx * dy - wy * dx
                if num_u < -utol * den or num_u > (1.0 + utol) * den:
                    continue  # the line is met beyond the ends of the edge
                t = num_t / den
                if t < best_e or (t == best_e and k < edge):
                    best_e, edge = t, k
            else:
                vx, vy = self._vertex_xy[k]
                cx, cy = px - vx, py - vy
                b = cx * dx + cy * dy
                c = cx * cx + cy * cy - self.radius * self.radius
                disc = b * b - c
                if b >= 0.0 or disc <= (GRAZE * self.radius) ** 2 or c < -2.0 * self.radius * tol:
                    continue  # moving away, missing, or already inside the circle
                t = max(-b - math.sqrt(disc), 0.0)
                if t < best_v or (t == best_v and k < vertex):
                    best_v, vertex = t, k
        if best_v < best_e:
            vx, vy = self._vertex_xy[vertex]
            qx, qy = px + best_v * dx - vx, py + best_v * dy - vy
            norm = math.hypot(qx, qy)
            return best_v, vertex, vertex, qx / norm, qy / norm
        if edge == NO_CONTACT:
            return math.inf, NO_CONTACT, NO_CONTACT, 0.0, 0.0
        nx, ny = self._normal_xy[edge]
        return max(best_e, 0.0), edge, NO_CONTACT, nx, ny

    def _refresh_lone(self, state: RobotState) -> tuple[float, int, float, float]:
        """`_refresh_hits` of a lone robot, in plain floats: ``(distance, edge, nx, ny)``."""
        self._engine()
        (dx, dy), = state.direction.tolist()  # numpy's cos and sin, as for many robots
        x, y = state.position[0].tolist()
        dist, edge, vertex, nx, ny = self._cast(x, y, dx, dy)
        self._hit_dist[0] = dist
        self._hit_edge[0] = edge
        self._hit_vertex[0] = vertex
        self._hit_normal[0] = nx, ny
        self._hit_origin[0] = x, y
        self._hit_heading[0] = state.heading[0]
        return dist, edge, nx, ny

    def _refresh_hits(self, state: RobotState, robots: np.ndarray) -> None:
        """Query the first wall hit of ``robots`` from their current pose into the cache."""
        self._engine()
        pos = state.position
        dirs = state.direction[robots]
        for j, i in enumerate(robots.tolist()):
            dist, edge, vertex, nx, ny = self._cast(
                float(pos[i, 0]), float(pos[i, 1]), float(dirs[j, 0]), float(dirs[j, 1])
            )
            self._hit_dist[i] = dist
            self._hit_edge[i] = edge
            self._hit_vertex[i] = vertex
            self._hit_normal[i] = (nx, ny)
        self._hit_origin[robots] = pos[robots]
        self._hit_heading[robots] = state.heading[robots]

    def _wall_distances(self, state: RobotState, robots: np.ndarray) -> np.ndarray:
        """Distance of each robot to the first wall ahead, from the cache where still valid."""
        stale = (state.heading[robots] != self._hit_heading[robots]) | np.any(
            state.position[robots] != self._hit_origin[robots], axis=1
        )
        if np.any(stale):
            self._refresh_hits(state, robots[stale])
        return self._hit_dist[robots]

    def _lone_wall_distance(self, state: RobotState) -> float:
        x, y = state.position[0].tolist()
        ox, oy = self._hit_origin[0].tolist()
        # NaN (no query yet) is unequal to anything
        if float(state.heading[0]) != float(self._hit_heading[0]) or x != ox or y != oy:
            return self._refresh_lone(state)[0]
        return float(self._hit_dist[0])

    # -- MotionBackend ----------------------------------------------------------------------
    def reset(self, state: RobotState) -> None:
        if state.n_robots != self.n_robots:
            raise ConfigError(
                f"state: expected {self.n_robots} robots, got {state.n_robots}"
            )
        self.check_start(state)
        if self._space is None:
            self._build_space()
        else:
            self._forget_engine_state()  # positions and velocities are rewritten before stepping
        self._hit_heading[:] = np.nan
        self.update_contacts(state, np.arange(state.n_robots))

    def update_contacts(self, state: RobotState, robots: np.ndarray) -> None:
        if state.n_robots == 1 and len(robots) == 1:  # no robot can block a lone one
            dist, edge, nx, ny = self._refresh_lone(state)
            wall = dist <= self.contact_tol
            state.contact_edge[0] = edge if wall else NO_CONTACT
            state.contact_normal[0] = nx, ny
            state.blocked[0] = wall
            return
        robots = np.asarray(robots, dtype=np.int64)
        if len(robots) == 0:
            return
        self._refresh_hits(state, robots)  # a pymunk query along the new heading
        self._classify_contacts(state, robots, robots, self._hit_dist[robots],
                                self._hit_edge[robots], self._hit_normal[robots])

    # Engine time is distance driven: robots move at unit speed and one tick lasts
    # ``step_length`` time units of the space, so a step of dt moves a robot by exactly
    # ``position + direction * dt``.
    def _start_drive(self) -> None:
        self._engine()
        self._synced = False  # positions may have been changed from outside since the last drive

    def _advance(self, state, moving, s_wall, ds, event):
        # conservative advancement: one physics step, to the event or to the window's end
        velocity = np.zeros_like(state.position)
        velocity[moving] = state.direction[moving]
        self._write_bodies(state, velocity)
        self._step(ds, event)
        bodies = self._bodies
        for i in moving.tolist():
            state.position[i] = bodies[i].position
        self._body_pos[moving] = state.position[moving]
        self._hit_origin[moving] = state.position[moving]
        self._hit_dist[moving] = s_wall - ds
        return ds

    def _lone_advance(self, state, s_wall, ds, event):
        (dx, dy), = state.direction.tolist()
        self._write_lone_body(state, [dx, dy])
        self._step(ds, event)
        x, y = self._bodies[0].position
        state.position[0] = x, y
        self._body_pos[0] = x, y
        self._hit_origin[0] = x, y
        self._hit_dist[0] = s_wall - ds
        return ds

    def _step(self, ds: float, event: bool) -> None:
        """One physics step of length ``ds`` (the bodies are up to date); with ``event``, the
        contacts the engine reports in it are recorded."""
        self._touching.clear()
        self._armed = event
        try:
            self._space.step(ds if ds > 0.0 else _SENSE_DT)
        finally:
            self._armed = False

    def _settle_contacts(self, state, walls, robots, pairs):
        walls_touched, pairs_touched = self._sensed()
        if len(walls):
            self._confirm_walls(state, walls, walls_touched)
            self._block_at_walls(state, walls, self._hit_edge[walls], self._hit_normal[walls])
        if len(robots):
            self._confirm_pairs(state, robots, pairs, pairs_touched)
            self._stop_touching(state, robots)

    def _lone_settle(self, state):
        self._confirm_wall(state, 0, {self._edge_of[wall] for _, wall in self._touching})
        state.blocked[0] = True
        state.contact_edge[0] = self._hit_edge[0]
        state.contact_robot[0] = NO_CONTACT
        state.contact_normal[0] = self._hit_normal[0]

    # -- helpers ----------------------------------------------------------------------------
    def _sensed(self) -> tuple[dict[int, set[int]], set[tuple[int, int]]]:
        """Contacts the engine reported in the last step: robot -> walls, and robot pairs."""
        walls: dict[int, set[int]] = {}
        pairs: set[tuple[int, int]] = set()
        robot_of, edge_of = self._robot_of, self._edge_of
        for a, b in self._touching:
            i = robot_of[a]
            k = edge_of.get(b)
            if k is None:
                j = robot_of[b]
                pairs.update(((i, j), (j, i)))
            else:
                walls.setdefault(i, set()).add(k)
        return walls, pairs

    def _confirm_pairs(self, state: RobotState, robots: np.ndarray, pairs: np.ndarray,
                       touched: set[tuple[int, int]]) -> None:
        """Every robot that reached another robot (``robots``; ``pairs``: the pairs predicted to
        touch) must be in a pair whose contact the engine's callback reported."""
        felt = set()
        for i, j in pairs.tolist():
            if (i, j) in touched:
                felt.update((i, j))
        for i in robots.tolist():
            if i not in felt:
                raise RuntimeError(
                    f"pymunk reported no contact for robot {i} at {state.position[i].tolist()} "
                    "although it reached another robot"
                )

    def _confirm_walls(
        self, state: RobotState, robots: np.ndarray, touched: dict[int, set[int]]
    ) -> None:
        """Every predicted wall contact must have been reported by the engine's callback."""
        for i in robots.tolist():
            self._confirm_wall(state, i, touched.get(i, set()))

    def _confirm_wall(self, state: RobotState, i: int, felt: set[int]) -> None:
        """Robot ``i`` reached its wall ahead: one of the edges it touches must be in ``felt``,
        the edges the engine reported touching it."""
        edge, vertex = int(self._hit_edge[i]), int(self._hit_vertex[i])
        if edge in felt or (vertex >= 0 and int(self._prev_edge[vertex]) in felt):
            return
        raise RuntimeError(
            f"pymunk reported no contact between robot {i} and edge {edge} at "
            f"{state.position[i].tolist()} although the robot reached it"
        )

