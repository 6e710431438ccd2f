"""The interface every motion backend implements, and the registry of backends by name.

A backend moves robots straight ahead and detects contacts; it knows nothing of bounce rules or
noise (those live in `bounce_gym.dynamics.BounceDynamics`, written once for all backends).

Time is measured in ticks. One tick drives a robot ``step_length`` (or less, if it touches
something first and stops). Robots that touch a wall or another robot while facing into it become
``blocked`` and stand still until the controller rotates them.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np
import shapely

from bounce_gym.dynamics.state import NO_CONTACT, RobotState
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World
from bounce_gym.worlds.raycast import GRAZE
from bounce_gym.worlds.world import sample_in

ROBOT_COLLISIONS = ("bounce", "ignore")
#: Consecutive rejected start positions after which random placement samples only the room left.
PLACEMENT_MISSES = 50
#: Candidates drawn at once from the room left when placement is crowded.
PLACEMENT_BATCH = 64


class MotionBackend(ABC):
    """Drives m robots in a world.

    Args:
        world: the workspace.
        n_robots: number of robots m.
        radius: robot disk radius (0 = point robot).
        step_length: distance driven per tick (the cell size of the cell model).
        robot_collisions: ``"bounce"`` (robots touching head-on are blocked, like walls) or
            ``"ignore"`` (robots pass through each other).
    """

    name: str = ""
    #: whether `drive_each` can move robots independently (no shared clock), which also gives
    #: `BounceDynamics` its scalar single-robot path
    drives_independently: bool = False
    #: orientation bin width (radians) if headings are discrete (the cell model), else None
    bin_width: float | None = None
    #: whether robots of radius 0 can still bump into each other (true on the cell grid)
    point_robots_collide: bool = False
    #: whether rotations take time (``physics="dynamic"``): then `BounceDynamics` hands them to
    #: `begin_turns` and `command_turns` instead of setting headings
    turns_take_time: bool = False
    #: degrees: the front arc, centred on the heading, whose contacts stop a robot (its bumper).
    #: The ideal robots are blocked by whatever they face into: the front half
    bumper_arc: float = 180.0
    #: how deep (world units) a start pose may overlap a wall or another robot: the ideal robots
    #: never overlap anything; a backend whose robots rest in contacts a hair deep (the dynamic
    #: physics) accepts its own states as starts
    start_depth: float = 0.0

    def __init__(
        self,
        world: World,
        n_robots: int,
        radius: float,
        step_length: float,
        robot_collisions: str,
    ) -> None:
        if not isinstance(world, World):
            raise ConfigError(f"world: expected a World, got {type(world).__name__}")
        if isinstance(n_robots, bool) or not isinstance(n_robots, int | np.integer) or n_robots < 1:
            raise ConfigError(f"n_robots: expected an integer >= 1, got {n_robots!r}")
        if not (np.isfinite(radius) and radius >= 0):
            raise ConfigError(f"robot_radius: expected a finite number >= 0, got {radius!r}")
        if not (np.isfinite(step_length) and step_length > 0):
            raise ConfigError(f"step_length: expected a finite number > 0, got {step_length!r}")
        if robot_collisions not in ROBOT_COLLISIONS:
            raise ConfigError(
                f"robot_collisions: expected one of {ROBOT_COLLISIONS}, got {robot_collisions!r}"
            )
        if robot_collisions == "bounce" and n_robots > 1 and radius <= 0 \
                and not self.point_robots_collide:
            raise ConfigError(
                "robot_collisions='bounce' needs robot_radius > 0 (point robots never touch); "
                "use robot_collisions='ignore' for point robots"
            )
        self.world = world
        self.n_robots = int(n_robots)
        self.radius = float(radius)
        self.step_length = float(step_length)
        self.robot_collisions = robot_collisions
        #: time tolerance in ticks, from the world's length tolerance
        self.time_tol = world.tol / self.step_length
        if self.collide and not self.point_robots_collide:  # disks, not grid cells
            self._check_packing()

    @property
    def collide(self) -> bool:
        return self.robot_collisions == "bounce" and self.n_robots > 1

    @property
    def contact_tol(self) -> float:
        """Distance at or below which a robot counts as touching what is ahead of it."""
        return 10.0 * self.world.tol

    @abstractmethod
    def reset(self, state: RobotState) -> None:
        """Take over a freshly placed state (rebuild any engine objects) and set its contacts."""

    @abstractmethod
    def update_contacts(self, state: RobotState, robots: np.ndarray) -> None:
        """Recompute ``blocked`` and the contact fields of ``robots`` (e.g. after a rotation)."""

    @abstractmethod
    def drive(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        """Drive every unblocked robot forward; robots stop where they become blocked.

        Stops after ``max_ticks`` ticks, or — with ``until_first_block`` — at the end of the tick
        in which the first robot becomes blocked (immediately, if one already is). Updates
        positions, contacts, odometers, clocks (+1 per tick each robot drove in) and
        ``state.ticks``. Returns the number of ticks elapsed.
        """

    def drive_each(self, state: RobotState) -> np.ndarray:
        """Drive every unblocked robot to its own next contact (see `drives_independently`)."""
        raise ConfigError(f"backend {self.name!r} does not drive robots independently")

    def begin_turns(self, state: RobotState, robots: np.ndarray, rotations: np.ndarray) -> None:
        """Start the bump turns of ``robots`` by ``rotations`` (see `turns_take_time`)."""
        raise ConfigError(f"backend {self.name!r} rotates robots instantly")

    def command_turns(self, state: RobotState, robots: np.ndarray,
                      rotations: np.ndarray) -> int:
        """Run a turn command of ``robots`` by ``rotations``; returns its ticks (see
        `turns_take_time`)."""
        raise ConfigError(f"backend {self.name!r} rotates robots instantly")

    def bumpers(self, state: RobotState) -> tuple[np.ndarray, np.ndarray]:
        """For drawings: (m,) whether each robot's bumper is pressed, and (m, 2) the unit normal
        (pointing at the robot) of the contact its bumper latched, NaN where none. An ideal
        robot's bumper is pressed while it is blocked, by the contact that blocks it."""
        blocked = state.blocked.copy()
        return blocked, np.where(blocked[:, None], state.contact_normal, np.nan)

    def phase_names(self) -> list[str] | None:
        """For drawings: each robot's motion phase by name, or None where motion has no phases
        beyond driving and being blocked (the ideal backends; `RobotState.blocked` says
        which)."""
        return None

    def check_start(self, state: RobotState) -> None:
        """Raise `ConfigError` unless every robot starts in the free space (``radius`` from the
        walls) and, when robots collide, no two overlap (both up to `start_depth`)."""
        inside = self.world.contains(state.position, self.radius - self.start_depth)
        if not inside.all():
            bad = int(np.flatnonzero(~inside)[0])
            raise ConfigError(
                f"start position of robot {bad} {state.position[bad].tolist()} is not in the free "
                f"space at distance >= robot_radius={self.radius} from the walls"
                + (f" (less {self.start_depth:.3g} of contact depth)" if self.start_depth else "")
            )
        if self.collide:
            diff = state.position[:, None, :] - state.position[None, :, :]
            dist = np.hypot(diff[..., 0], diff[..., 1])
            np.fill_diagonal(dist, np.inf)
            if np.any(dist < 2 * (self.radius - self.start_depth) - self.world.tol):
                i, j = np.unravel_index(np.argmin(dist), dist.shape)
                raise ConfigError(f"start positions of robots {i} and {j} overlap")

    def random_positions(self, rng: np.random.Generator) -> np.ndarray:
        """Uniform start positions in the free space (non-overlapping when robots collide).

        Colliding robots are placed one after another, each at a uniform point of the free space
        that overlaps no robot placed before (random sequential placement). Fails fast: at once
        when the robots' disks cover more than the free space they can reach (a necessary
        condition; checked on construction), and as soon as no room is left for the next robot.
        After `PLACEMENT_MISSES` straight misses it draws batches of `PLACEMENT_BATCH` points
        from the room left and seats every one that still fits, in turn (900 robots in the
        10 x 10 square: about 10 cuts of the room instead of one per robot).
        """
        if not self.collide:
            return self.world.sample_free(rng, self.n_robots, self.radius)
        n, gap = self.n_robots, 2 * self.radius
        chosen = np.empty((n, 2))
        k = misses = 0
        while k < n and misses < PLACEMENT_MISSES:
            p = self.world.sample_free(rng, 1, self.radius)[0]
            if np.all(np.hypot(*(chosen[:k] - p).T) > gap):
                chosen[k], k, misses = p, k + 1, 0
            else:
                misses += 1
        if k == n:
            return chosen
        # crowded: sample only where the next robot fits, until that room is gone. A batch of
        # candidates is uniform in the room as it was; taken in turn, each one that still fits
        # is uniform in the room left at its turn (rejection from a superset), so one cut of
        # the room seats a batch's worth of robots, not one.
        room = self.world.eroded(self.radius).difference(
            shapely.union_all(shapely.buffer(shapely.points(chosen[:k]), gap)))
        while k < n and room.area > self.world.tol**2:
            candidates = sample_in(room, rng, PLACEMENT_BATCH)
            ok = self.world.contains(candidates, self.radius)
            ok &= np.all(np.linalg.norm(candidates[:, None] - chosen[None, :k], axis=2) > gap,
                         axis=1)
            before = k
            for p in candidates[ok]:
                if k < n and np.all(np.hypot(*(chosen[before:k] - p).T) > gap):
                    chosen[k], k = p, k + 1
            if k == before:
                break
            room = room.difference(
                shapely.union_all(shapely.buffer(shapely.points(chosen[before:k]), gap)))
        if k == n:
            return chosen
        raise ConfigError(
            f"n_robots: placed {k} of {n} robots of robot_radius={self.radius} in world "
            f"{self.world.name!r} at random, then no room was left for the next one; use fewer "
            "or smaller robots, or give start positions"
        )

    def _check_packing(self) -> None:
        """Raise `ConfigError` if ``n_robots`` disjoint disks of ``radius`` cannot fit in the
        part of the free space that robot bodies can reach (its opening by the radius)."""
        reach = self.world.eroded(self.radius).buffer(self.radius).area
        cover = self.n_robots * math.pi * self.radius**2
        if cover > reach:
            fit = int(reach // (math.pi * self.radius**2))
            raise ConfigError(
                f"n_robots: {self.n_robots} robots of robot_radius={self.radius} cover "
                f"{cover:.4g}, more than the {reach:.4g} of free space they can reach in world "
                f"{self.world.name!r}; at most {fit} can fit"
            )

    # -- helpers shared by backends
    @staticmethod
    def _check_drive_window(max_ticks: float, until_first_block: bool) -> None:
        if not (until_first_block or math.isfinite(max_ticks)):
            raise ValueError("drive needs a finite max_ticks unless until_first_block is set")

    def _end_of_tick(self, elapsed: float) -> float:
        """The drive window (as distance) rounded up to the end of the current tick: a drive
        ``until_first_block`` stops at the end of the tick in which the first robot blocks."""
        step = self.step_length
        return max(math.ceil(elapsed / step - self.time_tol), 0) * step

    def _finish_drive(self, state: RobotState, driven: np.ndarray, limit: float,
                      elapsed: float) -> int:
        """Account a drive: every robot's clock gains the ticks it drove in, odometers the
        distance, the global clock the ticks of the window. Returns those ticks."""
        ticks = self._window_ticks(limit, elapsed)
        drove = np.ceil(driven / self.step_length - self.time_tol).astype(np.int64)
        state.clock += np.minimum(drove, ticks)
        state.odometer += driven
        state.ticks += ticks
        return ticks

    def _window_ticks(self, limit: float, elapsed: float) -> int:
        """Ticks of a drive window that closed at distance ``limit`` (``elapsed`` if endless)."""
        return math.ceil((limit if math.isfinite(limit) else elapsed) / self.step_length
                         - self.time_tol)

    @staticmethod
    def _block_at_walls(state: RobotState, robots: np.ndarray, edge: np.ndarray,
                        normal: np.ndarray) -> None:
        """Robots that reached a wall (``edge``, inward ``normal``) stop there, blocked."""
        state.blocked[robots] = True
        state.contact_edge[robots] = edge
        state.contact_robot[robots] = NO_CONTACT
        state.contact_normal[robots] = normal

    def _stop_touching(self, state: RobotState, robots: np.ndarray) -> None:
        """Block the robots of a disk–disk contact that face the robot they touch.

        Contact times are symmetric, so both robots of a pair are in ``robots``; at least one of
        two approaching robots faces the other, so every contact blocks someone.
        """
        blocker, normal = self.robot_blockers(state, robots)
        hit = blocker >= 0
        state.blocked[robots[hit]] = True
        state.contact_robot[robots[hit]] = blocker[hit]
        state.contact_edge[robots[hit]] = NO_CONTACT
        state.contact_normal[robots[hit]] = normal[hit]

    def _classify_contacts(self, state: RobotState, robots: np.ndarray, sel,
                           distance: np.ndarray, edge: np.ndarray, normal: np.ndarray) -> None:
        """Set ``blocked`` and the contact fields of ``robots`` from the wall ahead of each
        (``distance``, ``edge``, ``normal``) and, when robots collide, the robots they face.
        ``sel`` indexes the same robots (a slice where that is cheaper)."""
        wall = distance <= self.contact_tol
        state.contact_edge[sel] = np.where(wall, edge, NO_CONTACT)
        state.contact_normal[sel] = normal
        if not self.collide:
            state.blocked[sel] = wall
            return
        blocker, robot_normal = self.robot_blockers(state, robots)
        by_robot = ~wall & (blocker >= 0)
        state.blocked[robots] = wall | by_robot
        state.contact_robot[robots] = np.where(by_robot, blocker, NO_CONTACT)
        state.contact_normal[robots[by_robot]] = robot_normal[by_robot]

    def robot_blockers(self, state: RobotState, robots: np.ndarray):
        """For each of ``robots``: the touching robot it faces (or -1) and the contact normal.

        Robot i is blocked by robot j when the disks touch (within tolerance) and i's heading
        points towards j's centre; among several, the one most directly ahead (the lowest index
        among equals). Only robots within touching distance along both axes are examined further.
        """
        robots = np.asarray(robots, dtype=np.int64)
        blocker = np.full(len(robots), NO_CONTACT, dtype=np.int64)
        normal = np.zeros((len(robots), 2))
        if not self.collide or len(robots) == 0:
            return blocker, normal
        reach = 2 * self.radius + self.contact_tol
        pos = state.position
        rel_x = pos[:, 0] - pos[robots, 0, None]  # (robots, m): robot k -> robot j
        rel_y = pos[:, 1] - pos[robots, 1, None]
        near = (np.abs(rel_x) <= reach) & (np.abs(rel_y) <= reach)
        near[np.arange(len(robots)), robots] = False
        k, j = np.nonzero(near)  # row-major: by robot, then by the other's index
        x, y = rel_x[k, j], rel_y[k, j]
        dist = np.hypot(x, y)
        d = state.direction[robots]
        ahead = d[k, 0] * x + d[k, 1] * y
        # facing = heading within 90° − GRAZE of the other centre (a tangential touch is none)
        cand = (dist <= reach) & (ahead > GRAZE * np.maximum(dist, 1e-300))
        if np.any(cand):
            k, j, x, y = k[cand], j[cand], x[cand], y[cand]
            score = ahead[cand] / np.maximum(dist[cand], 1e-300)
            best = np.lexsort((j, -score, k))  # per robot: highest score, then lowest index
            first = best[np.r_[True, k[best][1:] != k[best][:-1]]]
            blocker[k[first]] = j[first]
            vec = np.column_stack((-x[first], -y[first]))
            normal[k[first]] = vec / np.hypot(vec[:, 0], vec[:, 1])[:, None]
        return blocker, normal


#: The robot index array of a lone robot.
_LONE = np.zeros(1, dtype=np.int64)
_LONE.flags.writeable = False
#: Consecutive zero-length events after which a drive declares itself stuck (a bug).
MAX_ZENO = 10_000
#: Relative margin of the broad phase of `pair_contacts`: pairs a little farther apart than two
#: robots can close in the window are examined too, so rounding never drops a contact.
BROAD_SLACK = 1e-3


class EventDrivenBackend(MotionBackend):
    """A continuous backend that advances all robots from one contact event to the next.

    `drive` is written once here: find each moving robot's distance to its wall ahead
    (`_wall_distances`) and, with collisions on, the first disk–disk contact of each pair that
    can meet before the nearest wall (`pair_contacts`, a broad phase then the exact times); move
    everyone to the earliest event or to the end of the window (`_advance`, the backend's own
    way of moving: closed form or one physics step); then stop the robots involved
    (`_settle_contacts`). Time is distance driven: one tick lasts ``step_length``.

    A lone robot takes `_drive_lone`, the same loop in plain floats through scalar versions of
    those hooks (the single-robot hot path); backends override them where numpy costs more than
    the work.
    """

    def drive(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        if state.n_robots == 1:
            return self._drive_lone(state, max_ticks, until_first_block)
        return self._drive_events(state, max_ticks, until_first_block)

    def _drive_events(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        """`drive` of any number of robots: from one contact event to the next."""
        if until_first_block and state.blocked.any():
            return 0
        self._check_drive_window(max_ticks, until_first_block)
        tol = self.contact_tol
        limit = float(max_ticks) * self.step_length
        driven = np.zeros(state.n_robots)
        elapsed, zeno = 0.0, 0
        self._start_drive()
        while elapsed < limit - tol:
            moving = np.flatnonzero(~state.blocked)
            if len(moving) == 0:
                break
            s_wall = self._wall_distances(state, moving)
            if not np.all(np.isfinite(s_wall)):
                lost = int(moving[~np.isfinite(s_wall)][0])
                raise RuntimeError(f"robot {lost} left the free space at {state.position[lost]}")
            s_robot = np.full(len(moving), np.inf)
            if self.collide:
                # only pairs that touch before the nearest wall and before the window closes
                # can change what happens next (`pair_contacts` finds exactly those): a later
                # contact is neither the next event nor due with it
                velocity = np.zeros_like(state.position)
                velocity[moving] = state.direction[moving]
                horizon = min(float(s_wall.min()), limit - elapsed) + tol
                first, second, s_pair = pair_contacts(state.position, velocity, self.radius,
                                                      horizon)
                soonest = np.full(state.n_robots, np.inf)
                np.minimum.at(soonest, first, s_pair)
                np.minimum.at(soonest, second, s_pair)
                s_robot = soonest[moving]
            s_next = float(min(s_wall.min(), s_robot.min()))
            ds = min(s_next, limit - elapsed)
            event = s_next <= ds + tol
            driven[moving] += self._advance(state, moving, s_wall, ds, event)
            elapsed += ds
            if not event:
                break  # the window closed before the next contact
            zeno = zeno + 1 if ds <= tol else 0
            if zeno > MAX_ZENO:
                raise RuntimeError(f"{self.name} integrator made no progress (contact "
                                   "bookkeeping bug)")
            walls = moving[s_wall <= s_next + tol]
            at_robot = s_robot <= s_next + tol
            pairs = None
            if self.collide:
                due = s_pair <= s_next + tol
                pairs = np.column_stack((first[due], second[due]))
            self._settle_contacts(state, walls, moving[at_robot], pairs)
            if until_first_block:
                limit = min(limit, self._end_of_tick(elapsed))
        return self._finish_drive(state, driven, limit, elapsed)

    def _drive_lone(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        """`drive` of a lone robot, in plain floats: `_drive_events`, which for one robot meets
        at most one event (no robot can stop it, and the wall it reaches blocks it), so the
        robot drives once — to its wall or to the end of the window — through the scalar hooks
        `_lone_wall_distance`, `_lone_advance` and `_lone_settle`."""
        blocked = bool(state.blocked[0])
        if until_first_block and blocked:
            return 0
        self._check_drive_window(max_ticks, until_first_block)
        tol = self.contact_tol
        limit = float(max_ticks) * self.step_length
        driven = elapsed = 0.0
        self._start_drive()
        if not blocked and elapsed < limit - tol:
            s_wall = self._lone_wall_distance(state)
            if not math.isfinite(s_wall):
                raise RuntimeError(f"robot 0 left the free space at {state.position[0]}")
            elapsed = min(s_wall, limit)
            event = s_wall <= elapsed + tol
            driven = self._lone_advance(state, s_wall, elapsed, event)
            if event:
                self._lone_settle(state)
                if until_first_block:
                    limit = min(limit, self._end_of_tick(elapsed))
        ticks = self._window_ticks(limit, elapsed)
        state.clock[0] += min(math.ceil(driven / self.step_length - self.time_tol), ticks)
        state.odometer[0] += driven
        state.ticks += ticks
        return ticks

    # The scalar hooks of `_drive_lone`, by default the array hooks applied to robot 0.
    def _lone_wall_distance(self, state: RobotState) -> float:
        """`_wall_distances` of a lone robot."""
        return float(self._wall_distances(state, _LONE)[0])

    def _lone_advance(self, state: RobotState, s_wall: float, ds: float, event: bool) -> float:
        """`_advance` of a lone robot (its wall ``s_wall`` ahead): the distance it drove."""
        drove = self._advance(state, _LONE, np.array([s_wall]), ds, event)
        return float(np.min(drove))  # one distance, as an array or a number

    def _lone_settle(self, state: RobotState) -> None:
        """`_settle_contacts` of a lone robot that reached its wall."""
        self._settle_contacts(state, _LONE, _LONE[:0], None)

    def _start_drive(self) -> None:
        """Hook called once at the start of every `drive`."""

    @abstractmethod
    def _wall_distances(self, state: RobotState, robots: np.ndarray) -> np.ndarray:
        """Distance each of ``robots`` drives before it touches its wall ahead."""

    @abstractmethod
    def _advance(self, state: RobotState, moving: np.ndarray, s_wall: np.ndarray, ds: float,
                 event: bool) -> np.ndarray | float:
        """Move the ``moving`` robots by ``ds`` (a robot whose wall is nearer stops there) and
        return the distance each drove; ``event`` says a contact is due at the end."""

    @abstractmethod
    def _settle_contacts(self, state: RobotState, walls: np.ndarray, robots: np.ndarray,
                         pairs: np.ndarray | None) -> None:
        """Stop the robots that reached a wall (``walls``) or another robot (``robots``; ``pairs``
        (k, 2): the robot pairs that touched, None when robots do not collide)."""


def pair_contacts(position: np.ndarray, velocity: np.ndarray, radius: float,
                  horizon: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Robot pairs whose disks start to touch within ``horizon``, and when.

    Robots move with constant ``velocity`` (unit speed or standing still). Returns
    ``(first, second, time)``: the pairs ``first < second`` (ascending by ``first``, then
    ``second``) with ``time <= horizon``, where ``time`` is the earliest t >= 0 at which
    |Δp + Δv t| = 2R while approaching. Pairs that never touch, separate, both stand still or
    only graze (the relative path meets the 2R circle at an angle below `GRAZE`, as for walls: two
    touching robots sliding past each other tangentially are not a contact) are left out.

    Broad phase: until ``horizon`` a robot stays within ``horizon / 2`` of the midpoint of its
    path, so two robots can only touch if those midpoints are within 2R + ``horizon``; pairs whose
    midpoints are farther apart along x or y (`close_pairs`) are never examined. The narrow phase
    solves the pairs left in closed form, exactly as a search over all pairs would
    (`contact_times`), so the result is the same, bit for bit.
    """
    reach = (2.0 * radius + horizon) * (1.0 + BROAD_SLACK)
    mid = position + velocity * (0.5 * horizon) if math.isfinite(horizon) else position
    first, second = close_pairs(mid, reach)
    time = contact_times(position[first] - position[second], velocity[first] - velocity[second],
                         radius)
    due = time <= horizon
    first, second, time = first[due], second[due], time[due]
    sort = np.lexsort((second, first))
    return first[sort], second[sort], time[sort]


def close_pairs(points: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Every pair of ``points`` (n, 2) at most ``reach`` apart along both x and y, as index arrays
    ``first < second`` (in no particular order).

    Sort and sweep: sorted by x, each point is paired with the following points up to ``reach``
    further along x, and those pairs are kept whose y are within ``reach`` too. O(n log n) plus
    the pairs within reach along x.
    """
    n = len(points)
    order = np.argsort(points[:, 0], kind="stable")
    xs = points[order, 0]
    # sorted position k is paired with k + 1 .. last[k] - 1
    last = np.searchsorted(xs, xs + reach, side="right")
    counts = last - np.arange(1, n + 1)
    k = np.repeat(np.arange(n), counts)
    partner = np.arange(len(k)) - np.repeat(np.cumsum(counts) - counts, counts) + k + 1
    a, b = order[k], order[partner]
    near = np.abs(points[a, 1] - points[b, 1]) <= reach
    return np.minimum(a[near], b[near]), np.maximum(a[near], b[near])


def contact_times(dp: np.ndarray, dv: np.ndarray, radius: float) -> np.ndarray:
    """First contact time of disk pairs with relative positions ``dp`` and velocities ``dv``
    ((n, 2) each), ``inf`` where they never touch: the narrow phase of `pair_contacts`."""
    a = dv[:, 0] * dv[:, 0] + dv[:, 1] * dv[:, 1]
    b = dp[:, 0] * dv[:, 0] + dp[:, 1] * dv[:, 1]
    c = (dp[:, 0] * dp[:, 0] + dp[:, 1] * dp[:, 1]) - (2 * radius) ** 2
    disc = b * b - a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / a
    # disc / a = (2R)² − (closest approach)²: at least sin²(GRAZE) · (2R)²
    ok = (b < 0) & (disc > a * (GRAZE * 2 * radius) ** 2) & (a > 0)
    return np.where(ok, np.maximum(t, 0.0), np.inf)
