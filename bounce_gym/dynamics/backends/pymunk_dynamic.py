"""``physics="dynamic"``: bouncing robots as rigid bodies with motors, a bumper and a clock.

Every robot is a pymunk body — mass, the moment of a uniform disk — in a space of static walls
(`bounce_gym.dynamics.backends.dynamic_engine`), and pymunk's solver resolves every contact with
the configured restitution and friction. Defaults: an iRobot Create 2
(`bounce_gym.dynamics.platform`, which cites the source of each number).

**Motors.** Nothing sets positions. At each *control instant* the controller sets the velocity
and turn rate of the coming period and the body jumps to them (the motors' impulse): the
**mean**, over the period, of a time-optimal continuous profile limited by ``max_acceleration``,
the turn acceleration 2 ``max_acceleration`` / ``wheel_base``, ``cruise_speed`` and
``turn_rate`` (`bounce_gym.dynamics.profiles`). The robot is therefore exactly where the
continuously accelerating robot would be at every instant; it moves at that mean in between.
Between instants the motors hold the set point against whatever the contacts do with a force of
at most mass × ``max_acceleration`` (the wheels' traction) and the matching torque. Instants come
every ``control_period`` h while a robot speeds up or brakes; a turn in place is commanded in
its own segments (speeding up, at the turn rate, slowing down): a disk turning in place changes
nothing the engine sees but its heading, which is exact at the segments' ends.

**The controller** of each robot is a state machine:

* ``DRIVE``: speed up along the heading to the cruise speed; the drive direction follows the
  body's heading. The **bumper** is the engine's contact callback restricted to the front arc: a
  contact point within ± ``bumper_arc`` / 2 of the heading presses it, and the robot brakes at
  once (a reflex, not waiting for an instant). The **stall** sensor backs it up, as the Create
  2's wheel overcurrent does: a driving robot that touches something and whose speed along its
  heading (the speed its wheels roll at) stays below ``stall_fraction`` of the commanded speed
  for ``stall_time`` seconds (defaults: half, 1 s) brakes too, latching the most frontal contact
  it touched. That is a robot wedged in a corner, pressing walls outside a narrow bumper arc, or
  pushed back or sideways by other robots — which the bumper alone would leave driving forever.
* ``BRAKE``: slow down at ``max_acceleration`` along the current velocity — a glancing robot
  slides along the wall meanwhile, friction slowing it too. At rest (speed and turn rate below
  1e-9 of their scales) it is **blocked**: ``RobotState.blocked`` is set, and the contact that
  pressed the bumper (the most frontal) is its ``contact_edge`` / ``contact_robot`` /
  ``contact_normal``, which the bounce rules read.
* ``BLOCKED``: hold still until given a bounce angle. The rule and the noise model
  (`bounce_gym.dynamics.BounceDynamics`) give the rotation to execute: counter-clockwise by φ
  plus the noise for Alam's relative rule (the papers' robots turn counter-clockwise by φ,
  "commanding a constant angular velocity for a fixed period of time": Alam, Bobadilla & Shell
  2018, §II), the shorter way to the new heading for the rules set by the boundary normal.
* ``TURN``: turn in place by that rotation, the time-optimal rest-to-rest profile; if contacts
  disturbed it, a correcting turn follows. A robot still moving when told to turn brakes first.
* ``WAIT``: turned; hold still until the next tick boundary, where the controller reads the
  bumper: pressed → blocked again (another bump, as when a rotation still faces the wall in the
  papers), else DRIVE from rest.
* ``HOLD``: a robot told to wait during a turn command (`command_turns`) brakes and holds; it
  drives on when the command ends.

**Every bounce step ends.** A driving robot whose bumper stays silent either keeps moving
along its heading at least at ``stall_fraction`` of its speed, or stalls within ``stall_time``.
The motors hold its heading (their torque exceeds the friction torque of a contact for every
friction below ``wheel_base`` / radius), and the world is bounded, so it meets something ahead
within the time to cross the world at that speed: its bumper or its stall stops it. A braking
robot is at rest within its braking time unless something pushes it — only a driving robot
does, until it stops; a turn ends once nothing disturbs it. Robots waiting at a tick boundary,
blocked or holding need no engine step: the clock moves on to the next event. Time advances at
every step, by at least a guard step.

**Ticks and the clock.** One tick lasts τ = ``step_length`` / cruise speed seconds, so
``step_length`` keeps its meaning: the distance driven in a tick at cruise speed. The bump tick
is the tick in which a blocked robot gets its angle and starts turning: its bump count rises and
its clock restarts at 0. Every later tick — turning, waiting, driving, braking — adds 1 to the
clock, so the clock counts the ticks since the last bump, turning time included. ``tick`` runs
one tick; ``bounce`` the bump tick and then ticks until the end of the tick in which some robot
is blocked, as on the exact backends. Turn commands (`command_turns`) last whole ticks, until
every commanded robot has turned; every clock advances by one per tick. The observations and
actions of the environments are unchanged.

**Stepping rule** (conservative advancement). pymunk moves each body in a step along a straight
segment, with the velocity it had when the step began, and only then integrates forces and
solves contacts. So before each step the motion of every robot in it is known exactly, and the
step is the longest that

* ends at the next event: a control instant, a tick boundary some robot waits for, the end of
  the drive window (when every robot stands still and waits, time moves on without a step);
* takes no robot more than half ``DEPTH`` (1e-7 radii) past its first touch with a wall or
  robot it does not touch yet: its path is cast against the walls (`bounce_gym.worlds.
  raycast.first_hit_scalar`, a swept disk of the radius less ``DEPTH``), robot pairs by the
  closed-form contact time of their relative motion (`bounce_gym.dynamics.backends.base.
  contact_times`). A free flight at cruise speed is therefore **one engine step** up to the
  wall, where the engine sees the overlap and the bumper fires;
* takes no robot deeper than ``TOUCH`` × ``DEPTH`` into what it already touches (from its
  approach speed; once that deep, by at most 1 % of that per step): the solver stops every
  approach, so only the motors' impulses and a stack's solver residuals approach a touched wall;
* moves a robot that touches something by at most half its radius.

A hundred solver iterations (ten times pymunk's default) keep a disk from creeping into a narrow
wedge of walls, where the two contact normals nearly oppose each other.

**Why nothing passes through a wall or a robot.** A step moves each robot along a known
segment, and ends before the segment takes it deeper than ``DEPTH`` into any wall or robot along
it — all are in the cast — or deeper than ``TOUCH`` × ``DEPTH`` (2e-5 radii, or by 1 % of that
a step beyond) into one it touches. To pass a wall (a zero-thickness segment) or a robot, a
robot's centre would have to come within less than its radius of it, half a radius at least
deeper than any step allows; and Chipmunk, whose collision test is discrete, sees every overlap
at the end of the step that makes it, while it is a hair deep, with its normal pointing the
right way, so the solver stops the approach (restitution ≤ 1). Only a guard step of 1e-9 ticks,
taken when a robot has crept to the limit, moves without the bound. The 1 % per step adds up
while driving robots press each other into a wall — a crowd whose narrow bumpers miss the
contacts, until the robots stall — because the solver has no position correction: the deepest
overlap measured over the adversarial suite's crowds is 2.7e-3 radii (0.5 mm on a Create 2),
three orders of magnitude short of a passage.

**Starts.** A robot is placed at rest. One placed with a wall (or, when robots collide, a
robot) within ``TRAVEL`` radii in its bumper arc reads its bumper as at a tick boundary and
starts blocked, the most frontal such contact latched — as the ideal backends read a contact
ahead at reset. A robot rests in its contacts up to ``TOUCH`` × ``DEPTH`` deep (the solver
corrects no overlap, so the overlap is part of the state), and a start may overlap walls and
robots that deep (`MotionBackend.start_depth`): a bump pose the simulator produced is a valid
start, reads as the same contact and continues as the robot that stopped there would.

**Determinism, pickling.** Randomness enters only through the angles given. The engine keeps no
state between steps but the bodies (`DynamicEngine`); pickling drops the pymunk space, and the
next drive rebuilds it from the robots' positions, angles, velocities and turn rates, stored
exactly, so a pickled and restored run continues bit for bit.

Renderers read each robot's phase and bumper: `phase` (codes of `PHASES`) or `phase_names`,
`bumper_pressed`, and `bumpers` (pressed, and the contact the bumper or the stall latched).
"""

from __future__ import annotations

import math

import numpy as np

from bounce_gym.dynamics.backends.base import MotionBackend, close_pairs, contact_times
from bounce_gym.dynamics.backends.dynamic_engine import ROBOT, WALL, DynamicEngine
from bounce_gym.dynamics.platform import PhysicsParams
from bounce_gym.dynamics.profiles import SlowDown, SpeedUp, Turn
from bounce_gym.dynamics.rules import TWO_PI
from bounce_gym.dynamics.state import NO_CONTACT, RobotState
from bounce_gym.errors import ConfigError
from bounce_gym.worlds.raycast import first_hit_scalar

DRIVE, BRAKE, BLOCKED, TURN, WAIT, HOLD = range(6)
NOTHING: frozenset = frozenset()
PHASES = ("drive", "brake", "blocked", "turn", "wait", "hold")
#: Deepest a robot may reach into a wall or another robot, relative to the radius; steps aim at
#: half of it.
DEPTH = 2e-7
#: What a robot touches it may reach this many times ``DEPTH`` into; beyond, a step deepens
#: a contact by at most 1 % of that. The solver stops every approach, so only kicks of the
#: motors and the residuals of a stack of contacts ever approach a touched wall or robot.
TOUCH = 50.0
#: A robot placed at rest reads its bumper pressed by a wall (or robot) this many radii away in
#: its bumper arc (8.5 mm on a Create 2, about a bumper's travel): a robot that glanced off a
#: wall corner and braked may stop a little clear of the contact it latched (measured up to
#: 7.9 mm in the tests' room with a pillar), and placed again at that pose it must read the
#: same contact, or a particle at the true pose would find no next bump.
TRAVEL = 0.05
#: A robot touching something moves at most this many radii per step.
CONTACT_REACH = 0.5
#: Speeds below this fraction of the cruise speed (turn rates below this fraction of
#: cruise speed / radius) count as rest.
REST = 1e-9
#: A turn is done when the heading is within this many radians of the target (else a
#: correcting turn follows).
TURN_TOL = 1e-12
#: Length of a guard step, in ticks, when a robot has crept to ``DEPTH``.
GUARD = 1e-9
#: Velocity directions (unit vectors) this close (L1) share their cast: the path then deviates
#: from the cached line by at most this fraction of its length, far below ``DEPTH``.
SAME_LINE = 1e-12
#: Consecutive guard steps after which a drive declares itself stuck (a bug).
MAX_GUARDS = 100_000
#: A bumper contact must lie this far (in cosine) inside the arc: an exactly tangential touch
#: does not press the bumper.
ARC_MARGIN = 1e-6


class _Robot:
    """One robot's body state (as last read from the engine) and controller state."""

    __slots__ = ("x", "y", "angle", "vx", "vy", "w", "phase", "speed", "tvx", "tvy", "tw",
                 "origin", "count", "next", "profile", "spin", "target", "settle",
                 "bump_tick", "commanded", "latch", "cast", "stall_at", "touch")

    def __init__(self, x: float, y: float, angle: float) -> None:
        self.x, self.y, self.angle = x, y, angle
        self.vx = self.vy = self.w = 0.0
        self.phase = DRIVE
        self.speed = 0.0  # DRIVE: the speed of the current period
        self.tvx = self.tvy = self.tw = 0.0  # other phases: the velocity of the current period
        #: the current profile's start, the instants since then, and the next instant
        self.origin, self.count, self.next = 0.0, 0, 0.0
        #: the current profile: SpeedUp (DRIVE), SlowDown (braking) or Turn (TURN)
        self.profile: SpeedUp | SlowDown | Turn | None = None
        self.spin: SlowDown | None = None  # braking: the turn rate's slow-down (signed by w)
        self.target = angle  # TURN: the unwrapped heading to reach
        self.settle = False  # TURN: braking to rest before turning
        self.bump_tick = False  # the current tick is this robot's bump tick
        self.commanded = False  # turning in the current turn command
        #: the contact that pressed the bumper: (kind, index, nx, ny), normal towards the robot
        self.latch: tuple[int, int, float, float] | None = None
        #: cached first wall along the velocity: (x, y, dx, dy, touched, distance, nx, ny)
        self.cast: tuple[float, ...] | None = None
        #: DRIVE: when the robot stalls if it stays slow (inf while it is not slow), and the
        #: most frontal contact it touched since it became slow, as ``latch``
        self.stall_at = math.inf
        self.touch: tuple[int, int, float, float] | None = None

    def __getstate__(self) -> dict:
        return {k: getattr(self, k) for k in self.__slots__}

    def __setstate__(self, state: dict) -> None:
        for k, v in state.items():
            setattr(self, k, v)


class DynamicBackend(MotionBackend):
    """Rigid-body robots with motors and bumpers; see the module docstring."""

    name = "pymunk"
    turns_take_time = True

    def __init__(self, world, n_robots, radius, step_length, robot_collisions,
                 params: PhysicsParams) -> None:
        if not radius > 0:
            raise ConfigError(f"robot_radius: physics='dynamic' simulates bodies of a size and "
                              f"needs robot_radius > 0, got {radius!r}")
        super().__init__(world, n_robots, radius, step_length, robot_collisions)
        self.params = params
        scale = params.world_scale
        self.cruise = params.cruise_speed / scale  # world units per second
        self.accel = params.max_acceleration / scale
        self.turn_rate = math.radians(params.turn_rate)
        self.turn_accel = params.turn_acceleration
        self.period = params.control_period
        #: seconds per tick
        self.tick_seconds = self.step_length / self.cruise
        self.bumper_arc = params.bumper_arc
        self.cos_arc = math.cos(math.radians(params.bumper_arc) / 2) + ARC_MARGIN
        self.stall_fraction, self.stall_time = params.stall_fraction, params.stall_time
        self.depth = DEPTH * self.radius
        #: a robot rests in its contacts up to this deep (the stepping rule's bound; the solver
        #: corrects no overlap), so its own bump poses are valid starts (module docstring)
        self.start_depth = TOUCH * self.depth
        self._rest_v = REST * self.cruise
        self._rest_w = REST * self.cruise / self.radius
        self.engine = DynamicEngine(world, self.n_robots, self.radius, params.mass,
                                    params.restitution, params.friction, params.iterations,
                                    self.collide)
        self._robots: list[_Robot] = []
        #: per wall: start, direction and squared length, as plain floats
        self._segments = [(a[0], a[1], b[0] - a[0], b[1] - a[1],
                           (b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2)
                          for a, b in zip(world.edge_start.tolist(), world.edge_end.tolist(),
                                          strict=True)]
        self._now = 0.0  # seconds since reset
        self._tick = 0  # ticks since reset
        self._commanding = False
        self._placed = False  # whether the engine's bodies hold the robots' state

    # -- renderer hooks -----------------------------------------------------------------------
    @property
    def phase(self) -> np.ndarray:
        """(m,) phase of every robot, an index into `PHASES`."""
        return np.array([r.phase for r in self._robots], dtype=np.int8)

    @property
    def bumper_pressed(self) -> np.ndarray:
        """(m,) whether each robot's bumper is pressed by a contact of the last engine step."""
        return np.array([self._pressed(i, r) is not None for i, r in enumerate(self._robots)])

    def bumpers(self, state: RobotState) -> tuple[np.ndarray, np.ndarray]:
        """(m,) `bumper_pressed`, and (m, 2) the normal (pointing at the robot) of the contact
        each robot's bumper or stall sensor latched — from the moment it fires, through braking
        and standing blocked, until the robot turns — NaN where none."""
        normal = np.full((self.n_robots, 2), np.nan)
        for i, r in enumerate(self._robots):
            if r.latch is not None:
                normal[i] = r.latch[2:]
        return self.bumper_pressed, normal

    def phase_names(self) -> list[str]:
        """Each robot's phase by name (`PHASES`)."""
        return [PHASES[r.phase] for r in self._robots]

    # -- MotionBackend ------------------------------------------------------------------------
    def reset(self, state: RobotState) -> None:
        if state.n_robots != self.n_robots:
            raise ConfigError(f"state: expected {self.n_robots} robots, got {state.n_robots}")
        self.check_start(state)
        self._robots = [_Robot(float(p[0]), float(p[1]), float(h))
                        for p, h in zip(state.position, state.heading, strict=True)]
        for r in self._robots:
            r.profile = SpeedUp(self.cruise, self.accel)
        self._now, self._tick, self._commanding = 0.0, 0, False
        self.engine.contacts = []
        self._placed = False
        for i, latch in self._start_contacts(state):  # at rest with the bumper pressed
            r = self._robots[i]
            r.phase, r.latch, r.next = BLOCKED, latch, math.inf
        self.update_contacts(state, np.arange(self.n_robots))

    def _start_contacts(self, state: RobotState) -> list[tuple[int, tuple[int, int, float, float]]]:
        """The robots placed with their bumper pressed — a wall or (when robots collide) a robot
        within ``TRAVEL`` radii in the bumper arc — and the most frontal such contact of
        each, as a latch: what a robot at rest reads at a tick boundary, from the geometry
        (the engine has not stepped yet)."""
        pos, heading = state.position, state.heading
        direction = np.column_stack((np.cos(heading), np.sin(heading)))
        travel = max(self.contact_tol, TRAVEL * self.radius)
        reach = self.radius + travel
        best = np.full(len(pos), self.cos_arc)
        latch: dict[int, tuple[int, int, float, float]] = {}
        start, vec = self.world.edge_start, self.world.edge_end - self.world.edge_start
        length2 = np.einsum("ij,ij->i", vec, vec)
        chunk = max(1, 2**20 // max(len(vec), 1))
        for lo in range(0, len(pos), chunk):
            rel = pos[lo:lo + chunk, None, :] - start[None, :, :]  # (robots, walls, 2)
            u = np.clip(np.einsum("rwk,wk->rw", rel, vec) / length2, 0.0, 1.0)
            away = rel - u[..., None] * vec  # from the nearest wall point to the centre
            dist = np.hypot(away[..., 0], away[..., 1])
            ahead = -np.einsum("rwk,rk->rw", away, direction[lo:lo + chunk]) \
                / np.maximum(dist, 1e-300)
            ahead = np.where(dist <= reach, ahead, -np.inf)
            k = np.argmax(ahead, axis=1)
            rows = np.arange(len(k))
            front = ahead[rows, k]
            for j in np.flatnonzero(front > best[lo:lo + chunk]).tolist():
                i = lo + j
                n = away[j, k[j]] / dist[j, k[j]]
                best[i] = front[j]
                latch[i] = (WALL, int(k[j]), float(n[0]), float(n[1]))
        if self.collide:
            for i, j in zip(*close_pairs(pos, 2 * self.radius + travel), strict=True):
                gap = pos[j] - pos[i]
                dist = float(np.hypot(*gap))
                if dist > 2 * self.radius + travel or dist == 0.0:
                    continue
                for a, b, sign in ((int(i), int(j), 1.0), (int(j), int(i), -1.0)):
                    front = sign * float(gap @ direction[a]) / dist
                    if front > best[a]:
                        best[a] = front
                        latch[a] = (ROBOT, b, -sign * gap[0] / dist, -sign * gap[1] / dist)
        return sorted(latch.items())

    def update_contacts(self, state: RobotState, robots: np.ndarray) -> None:
        """Blocked robots are those whose controller is in BLOCKED; write their contacts."""
        for i in np.asarray(robots, dtype=np.int64).tolist():
            self._write_contact(state, i, self._robots[i])

    @staticmethod
    def _write_contact(state: RobotState, i: int, r: _Robot) -> None:
        """Robot ``i``'s blocked flag and contact, from its controller."""
        blocked = r.phase == BLOCKED
        state.blocked[i] = blocked
        if blocked and r.latch is not None:
            kind, k, nx, ny = r.latch
            state.contact_edge[i] = k if kind == WALL else NO_CONTACT
            state.contact_robot[i] = k if kind == ROBOT else NO_CONTACT
            state.contact_normal[i] = nx, ny
        else:
            state.contact_edge[i] = NO_CONTACT
            state.contact_robot[i] = NO_CONTACT

    def drive(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        if until_first_block and np.count_nonzero(state.blocked):
            return 0
        self._check_drive_window(max_ticks, until_first_block)
        end = None if until_first_block else self._tick + int(max_ticks)
        return self._run(state, end, until_first_block)

    def begin_turns(self, state: RobotState, robots: np.ndarray, rotations) -> None:
        """Bump ticks of ``robots``: each starts turning in place by its rotation (radians,
        counter-clockwise positive; an array or a list). The caller counts the bump and
        restarts the clock."""
        for i, rotation in zip(robots.tolist(), list(rotations), strict=True):
            r = self._robots[i]
            self._start_turn(r, float(rotation))
            r.bump_tick = True
            self._write_contact(state, i, r)

    def command_turns(self, state: RobotState, robots: np.ndarray,
                      rotations: np.ndarray) -> int:
        """A turn command: ``robots`` turn in place by ``rotations`` (radians, counter-clockwise
        positive; added to a turn in progress); every driving robot brakes and holds. The command
        lasts until every commanded robot has turned, rounded up to whole ticks (at least one);
        then the waiting robots drive on. Every clock advances by one per tick. Returns the
        ticks."""
        for r in self._robots:
            if r.phase == DRIVE:
                r.phase = HOLD
                self._start_brake(r)
        for i, rotation in zip(robots.tolist(), rotations.tolist(), strict=True):
            r = self._robots[i]
            if r.phase == TURN:
                r.target += rotation
            else:
                self._start_turn(r, rotation)
            r.commanded = True
            state.blocked[i] = False
        self.update_contacts(state, robots)
        self._commanding = True
        return self._run(state, None, False)

    # -- the drive loop -----------------------------------------------------------------------
    def _run(self, state: RobotState, end: int | None, until_first_block: bool) -> int:
        """Step the engine from the current tick boundary until tick ``end`` (None: until the
        command ends, or — ``until_first_block`` — the end of the tick in which a robot
        blocks). Returns the ticks elapsed."""
        self._prepare_engine()
        start = self._tick
        tau = self.tick_seconds
        guards = 0
        while True:
            self._decide(state)
            at_boundary = self._now == self._tick * tau
            event, resting, blocked = self._next_event(end)
            if until_first_block and end is None and blocked:
                end = self._tick if at_boundary else self._tick + 1
                event = min(event, end * tau)
            if self._commanding and at_boundary and self._tick > start and self._command_done():
                end = self._tick  # the window closes here, at this boundary
                self._commanding = False
                self._release(state)
            if end is not None and self._tick >= end and at_boundary:
                break
            if resting:
                if not math.isfinite(event):
                    raise RuntimeError("pymunk dynamic: nothing moves and nothing is awaited")
                self._advance_clock(state, event)  # nothing moves: no engine step needed
                if self._now == self._tick * tau:
                    self._boundary(state)
                continue
            safe = self._safe_interval(event - self._now)
            if safe < event - self._now:
                if safe < GUARD * tau:
                    guards += 1
                    if guards > MAX_GUARDS:
                        raise RuntimeError("pymunk dynamic: robots are stuck at the contact "
                                           "depth (stepping bug)")
                    safe = GUARD * tau
                else:
                    guards = 0
                dt, now = safe, self._now + safe
            elif math.isfinite(event):
                dt, now = event - self._now, event
            else:
                raise RuntimeError("pymunk dynamic: nothing moves and nothing is awaited")
            self._step(state, dt)
            self._advance_clock(state, now)
            self._bumpers()
            if self._now == self._tick * tau:
                self._boundary(state)
        elapsed = self._tick - start
        state.ticks += elapsed
        self._write_state(state)
        return elapsed

    def _prepare_engine(self) -> None:
        """Put the robots into the engine (after a reset or unpickling) and make its contact
        order canonical (`DynamicEngine.canonicalize`)."""
        if not self._placed:
            robots = self._robots
            self.engine.set_bodies(np.array([[r.x, r.y] for r in robots]),
                                   np.array([r.angle for r in robots]),
                                   np.array([[r.vx, r.vy] for r in robots]),
                                   np.array([r.w for r in robots]))
            self._placed = True
        self.engine.canonicalize()

    def _next_event(self, end: int | None) -> tuple[float, bool, bool]:
        """The earliest control instant, waited-for tick boundary or window end (inf if none:
        then only the stepping rule ends the step); whether every robot stands still with no
        decision due (waiting or blocked: no engine step is needed until then); and whether some
        robot is blocked."""
        event = math.inf if end is None else end * self.tick_seconds
        waiting, resting, blocked = False, True, False
        for r in self._robots:
            if r.next < event:
                event = r.next
            phase = r.phase
            if phase == DRIVE and r.touch is not None and r.stall_at < event:
                event = r.stall_at  # it stalls then if it stays slow
            blocked = blocked or phase == BLOCKED
            waiting = waiting or phase == WAIT or (phase == HOLD and self._commanding)
            resting = resting and r.next == math.inf and phase != DRIVE and r.vx == 0.0 \
                and r.vy == 0.0 and r.w == 0.0
        if waiting or self._commanding:  # a command ends at a tick boundary
            event = min(event, (self._tick + 1) * self.tick_seconds)
        return event, resting, blocked

    def _advance_clock(self, state: RobotState, now: float) -> None:
        """Move the time to ``now``; every tick boundary passed adds a tick to every clock but
        that of a robot in its bump tick."""
        tau = self.tick_seconds
        while (self._tick + 1) * tau <= now:
            self._tick += 1
            for i, r in enumerate(self._robots):
                if r.bump_tick:
                    r.bump_tick = False
                else:
                    state.clock[i] += 1
        self._now = now

    def _write_state(self, state: RobotState) -> None:
        for i, r in enumerate(self._robots):
            state.position[i] = r.x, r.y
            heading = r.angle % TWO_PI
            state.heading[i] = 0.0 if heading >= TWO_PI else heading  # -1e-20 % 2π is 2π

    # -- one engine step ----------------------------------------------------------------------
    def _step(self, state: RobotState, dt: float) -> None:
        """Push every robot towards its set points for ``dt`` seconds, step and read the
        bodies."""
        engine = self.engine
        mass, moment = engine.mass, engine.moment
        fmax, tmax = self.accel * dt, self.turn_accel * dt
        for i, r in enumerate(self._robots):
            if r.phase == DRIVE:
                tvx, tvy = r.speed * math.cos(r.angle), r.speed * math.sin(r.angle)
            else:
                tvx, tvy = r.tvx, r.tvy
            dvx, dvy, dw = tvx - r.vx, tvy - r.vy, r.tw - r.w
            if dvx == 0.0 and dvy == 0.0 and dw == 0.0:
                continue  # on its set points: no force (the engine clears forces every step)
            norm = math.hypot(dvx, dvy)
            if norm > fmax:  # traction: at most mass x max_acceleration
                dvx, dvy = dvx * (fmax / norm), dvy * (fmax / norm)
            if abs(dw) > tmax:
                dw = math.copysign(tmax, dw)
            engine.push(i, mass * dvx / dt, mass * dvy / dt, moment * dw / dt)
        engine.step(dt)
        odometer = state.odometer
        for i, (r, (x, y, angle, vx, vy, w)) in enumerate(zip(self._robots, engine.read(),
                                                               strict=True)):
            travelled = math.hypot(x - r.x, y - r.y)
            odometer[i] += travelled
            cast = r.cast
            if cast is not None and cast[0] == r.x and cast[1] == r.y and travelled > 0.0:
                speed = math.hypot(vx, vy)
                if speed > 0.0 and abs(cast[2] - vx / speed) + abs(cast[3] - vy / speed) \
                        <= SAME_LINE:
                    # on along the same line: the first wall along it is the same, nearer
                    r.cast = (x, y, *cast[2:5], cast[5] - travelled, cast[6], cast[7])
            r.x, r.y, r.angle, r.vx, r.vy, r.w = x, y, angle, vx, vy, w

    def _bumpers(self) -> None:
        """Driving robots whose bumper is pressed, or whose wheels stall, brake, starting
        now."""
        for i, r in enumerate(self._robots):
            if r.phase == DRIVE:
                latch = self._pressed(i, r)
                if latch is None:
                    latch = self._stalled(i, r)
                if latch is not None:
                    r.phase, r.latch = BRAKE, latch
                    self._start_brake(r)

    def _pressed(self, i: int, r: _Robot,
                 front: float | None = None) -> tuple[int, int, float, float] | None:
        """The most frontal contact of robot ``i`` in its bumper arc (or, given ``front``, the
        cosine of its angle off the heading above that) in the last step, as (kind, index, nx,
        ny) with the normal pointing at the robot; None if none."""
        dx, dy = math.cos(r.angle), math.sin(r.angle)
        best, front = None, self.cos_arc if front is None else front
        for _, kind, k, nx, ny in self.engine.contacts_of(i):
            ahead = nx * dx + ny * dy
            if ahead > front:
                best, front = (kind, k, -nx, -ny), ahead
        return best

    def _stalled(self, i: int, r: _Robot) -> tuple[int, int, float, float] | None:
        """The wheel overcurrent of a driving robot ``i`` whose bumper is silent: the contact
        to latch if it has been slow (see the module docstring) for ``stall_time`` and touched
        something meanwhile, else None. Its velocity holds until the next step, so a robot
        slow after every step since it became slow has been slow throughout."""
        forward = r.vx * math.cos(r.angle) + r.vy * math.sin(r.angle)
        if forward >= self.stall_fraction * r.speed:
            r.stall_at, r.touch = math.inf, None
            return None
        if r.stall_at == math.inf:
            r.stall_at = self._now + self.stall_time
        touch = self._pressed(i, r, -2.0)  # any contact, the most frontal
        if touch is not None:
            r.touch = touch
        return r.touch if self._now >= r.stall_at and r.touch is not None else None

    # -- the stepping rule --------------------------------------------------------------------
    def _safe_interval(self, horizon: float) -> float:
        """The longest step (at most ``horizon``) in which no robot gets more than ``DEPTH``
        deep into a wall or robot it does not touch yet, nor more than ``TOUCH`` x ``DEPTH``
        into one it touches (see the module docstring)."""
        walls: dict[int, set[int]] = {}
        pairs: set[tuple[int, int]] = set()
        limit = horizon
        robots = self._robots
        contacts = self.engine.contacts
        for i, kind, k, nx, ny in contacts:  # what each robot touches
            r = robots[i]
            if kind == WALL:
                # the solver's, not the cast's: a wall it slides along or leaves cannot come
                # nearer along its straight path (a segment is convex), and casting a disk that
                # already overlaps it would stall the step
                walls.setdefault(i, set()).add(k)
                approach = r.vx * nx + r.vy * ny
                if approach > 0.0:
                    limit = min(limit, self._touch_limit(
                        approach, self.radius - self._edge_distance(r, k)))
            elif i < k:
                o = robots[k]
                pairs.add((i, k))
                gap = math.hypot(o.x - r.x, o.y - r.y)
                limit = min(limit, self._touch_limit((r.vx - o.vx) * nx + (r.vy - o.vy) * ny,
                                                     2 * self.radius - gap))
        slow = 0.5 * self.depth / limit  # slower robots cannot get half DEPTH deep in time
        touching = {c[0] for c in contacts} if contacts else NOTHING
        for i, r in enumerate(robots):
            speed = math.hypot(r.vx, r.vy)
            if speed <= slow:
                continue
            touched = frozenset(walls[i]) if i in walls else NOTHING
            limit = min(limit, self._wall_reach(r, speed, touched) / speed)
            if i in touching:
                limit = min(limit, CONTACT_REACH * self.radius / speed)
        if self.collide:
            limit = min(limit, self._pair_reach(limit, pairs))
        return limit

    def _touch_limit(self, approach: float, depth: float) -> float:
        """The longest step in which a contact of ``depth`` approached at speed ``approach``
        stays within ``TOUCH`` x ``DEPTH`` — or deepens by 1 % of that, once beyond."""
        if approach <= 0.0:
            return math.inf
        room = TOUCH * self.depth
        return max(room - depth, 0.01 * room) / approach

    def _edge_distance(self, r: _Robot, k: int) -> float:
        """Distance from the robot's centre to wall segment ``k``."""
        ax, ay, ex, ey, length2 = self._segments[k]
        u = min(max(((r.x - ax) * ex + (r.y - ay) * ey) / length2, 0.0), 1.0)
        return math.hypot(r.x - ax - u * ex, r.y - ay - u * ey)

    def _wall_reach(self, r: _Robot, speed: float, touched: frozenset) -> float:
        """Distance the robot may travel along its velocity before it is half ``DEPTH`` (or,
        already that deep, ``DEPTH``) into a wall it approaches and does not touch yet (the
        walls in ``touched``, and their end vertices, are the solver's)."""
        dx, dy = r.vx / speed, r.vy / speed
        cast = r.cast
        if cast is not None and cast[0] == r.x and cast[1] == r.y and cast[4] == touched \
                and abs(cast[2] - dx) + abs(cast[3] - dy) <= SAME_LINE:
            distance, nx, ny = cast[5], cast[6], cast[7]
        else:
            distance, _, _, nx, ny = first_hit_scalar(self.world, r.x, r.y, dx, dy,
                                                      self.radius - self.depth, touched)
            r.cast = (r.x, r.y, dx, dy, touched, distance, nx, ny)
        approach = -(dx * nx + dy * ny)  # depth gained per unit travelled
        if approach <= 0.0:
            return distance
        # half DEPTH past the first touch, along the path: as deep as the angle makes it
        early = distance - self.depth / approach + 0.5 * self.depth
        return early if early > 0.0 else distance

    def _pair_reach(self, horizon: float, touching: set[tuple[int, int]]) -> float:
        """The longest step (at most ``horizon``) in which no two approaching robots that do
        not touch yet get closer than 2 radii − ``DEPTH``, stopping at half that depth."""
        robots = self._robots
        position = np.array([[r.x, r.y] for r in robots])
        velocity = np.array([[r.vx, r.vy] for r in robots])
        if not np.any(velocity):
            return horizon
        fastest = float(np.max(np.hypot(velocity[:, 0], velocity[:, 1])))
        span = fastest * horizon if math.isfinite(horizon) else math.inf
        if math.isfinite(span):
            first, second = close_pairs(position + 0.5 * horizon * velocity,
                                        (2 * self.radius + span) * 1.001)
        else:
            first, second = close_pairs(position, math.inf)
        if touching:
            free = np.array([(i, j) not in touching for i, j in zip(first.tolist(),
                                                                     second.tolist(),
                                                                     strict=True)], dtype=bool)
            first, second = first[free], second[free]
        if len(first) == 0:
            return horizon
        dp, dv = position[first] - position[second], velocity[first] - velocity[second]
        touch = contact_times(dp, dv, self.radius)  # inf for pairs that never touch
        with np.errstate(divide="ignore"):  # ... such as pairs moving alike
            # half DEPTH past the first touch, along the relative path
            times = touch + 0.5 * self.depth / np.hypot(dv[:, 0], dv[:, 1])
        return min(horizon, float(times.min()))

    # -- the controller -----------------------------------------------------------------------
    def _decide(self, state: RobotState) -> None:
        """Run the control instants that are due."""
        for i, r in enumerate(self._robots):
            if r.next <= self._now:
                self._instant(state, i, r)

    def _instant(self, state: RobotState, i: int, r: _Robot) -> None:
        """A control instant of robot ``i``: set the velocity and turn rate of the coming period
        to the means of its profile over the period (the motors' impulse)."""
        h = self.period
        t = self._now - r.origin
        r.count += 1
        r.next = r.origin + r.count * h
        end = r.next - r.origin
        if r.phase == DRIVE:
            if t >= r.profile.duration:
                r.speed, r.next = self.cruise, math.inf  # cruising until the bumper fires
            else:
                r.speed = r.profile.mean(t, end, r.next - self._now)
            c, s = math.cos(r.angle), math.sin(r.angle)
            self._kick(i, r, r.speed * c, r.speed * s, 0.0)
        elif r.phase in (BRAKE, HOLD) or (r.phase == TURN and r.settle):
            if t < max(r.profile.duration, r.spin.duration):
                # never faster than now: contacts may have slowed the robot below its profile
                speed = math.hypot(r.vx, r.vy)
                span = r.next - self._now
                keep = min(r.profile.mean(t, end, span) / speed, 1.0) if speed > 0.0 else 0.0
                spin = math.copysign(min(r.spin.mean(t, end, span), abs(r.w)), r.w)
                self._kick(i, r, r.vx * keep, r.vy * keep, spin)
                return
            self._kick(i, r, 0.0, 0.0, 0.0)
            if not self._at_rest(r):  # pushed meanwhile: brake again from here
                self._start_brake(r)
                self._instant(state, i, r)
            elif r.phase == BRAKE:
                r.phase, r.next = BLOCKED, math.inf
                self._write_contact(state, i, r)
            elif r.phase == HOLD:
                r.next = math.inf
            else:
                r.settle = False
                self._plan_turn(state, i, r)
        elif self._now < r.origin + r.profile.duration:  # TURN (ends at that very instant)
            # a turn in place is commanded in its segments — speeding up, at the turn rate,
            # slowing down — each at its mean rate: the heading is exact at their ends, and
            # turning a disk in place changes nothing else the engine sees
            turn = r.profile
            r.next = self._next_break(r.origin, turn)
            end = r.next - r.origin
            self._kick(i, r, 0.0, 0.0, turn.mean(t, end, r.next - self._now),
                       max(h, turn.ramp))
        else:
            self._kick(i, r, 0.0, 0.0, 0.0, max(h, r.profile.ramp))
            if abs(r.target - r.angle) > TURN_TOL:
                self._plan_turn(state, i, r)  # a correction: contacts disturbed the turn
            else:
                r.phase, r.next = WAIT, math.inf

    def _next_break(self, origin: float, turn: Turn) -> float:
        """The first end of a segment of ``turn`` (started at ``origin``) after now."""
        now, first = self._now, math.inf
        for at in (origin + turn.ramp, origin + turn.plateau_end(), origin + turn.duration):
            if now < at < first:
                first = at
        return first

    def _kick(self, i: int, r: _Robot, vx: float, vy: float, w: float,
              seconds: float | None = None) -> None:
        """Set the velocity and turn rate of the coming period (segment); the body jumps to
        them, by at most the change the motors make in ``seconds`` (default: a period) at
        ``max_acceleration`` and the turn acceleration."""
        r.tvx, r.tvy, r.tw = vx, vy, w
        seconds = self.period if seconds is None else seconds
        dvx, dvy, dw = vx - r.vx, vy - r.vy, w - r.w
        budget = self.accel * seconds
        norm = math.hypot(dvx, dvy)
        if norm > budget:
            vx, vy = r.vx + dvx * (budget / norm), r.vy + dvy * (budget / norm)
        if abs(dw) > self.turn_accel * seconds:
            w = r.w + math.copysign(self.turn_accel * seconds, dw)
        if (vx, vy, w) != (r.vx, r.vy, r.w):
            r.vx, r.vy, r.w = vx, vy, w
            self.engine.set_velocity(i, vx, vy, w)

    def _start_turn(self, r: _Robot, rotation: float) -> None:
        r.phase, r.latch = TURN, None
        r.target = r.angle + rotation
        r.settle = True  # brake to rest first (at once when at rest)
        self._start_brake(r)

    def _start_brake(self, r: _Robot) -> None:
        """Slow the robot (and its spin) to rest from its current velocity, from now."""
        r.profile = SlowDown(math.hypot(r.vx, r.vy), self.accel)
        r.spin = SlowDown(abs(r.w), self.turn_accel)
        self._restart_grid(r)

    def _restart_grid(self, r: _Robot) -> None:
        """Control instants from now on: now, now + h, now + 2h, ..."""
        r.origin, r.count, r.next = self._now, 0, self._now

    def _plan_turn(self, state: RobotState, i: int, r: _Robot) -> None:
        """Turn from rest towards ``r.target``, starting at this instant."""
        delta = r.target - r.angle
        if delta == 0.0:
            r.phase, r.next = WAIT, math.inf
            return
        r.profile = Turn(delta, self.turn_rate, self.turn_accel, self.period)
        self._restart_grid(r)
        self._instant(state, i, r)

    def _at_rest(self, r: _Robot) -> bool:
        return math.hypot(r.vx, r.vy) <= self._rest_v and abs(r.w) <= self._rest_w

    def _command_done(self) -> bool:
        return all(not r.commanded or r.phase == WAIT for r in self._robots)

    def _boundary(self, state: RobotState) -> None:
        """A tick boundary: waiting robots read their bumper (pressed → blocked, else drive);
        during a turn command they wait for its end."""
        if self._commanding:
            return
        for i, r in enumerate(self._robots):
            if r.phase == WAIT:
                self._leave_rest(state, i, r)

    def _release(self, state: RobotState) -> None:
        """The end of a turn command: turned and holding robots read their bumper."""
        for i, r in enumerate(self._robots):
            r.commanded = False
            if r.phase in (WAIT, HOLD):
                self._leave_rest(state, i, r)

    def _leave_rest(self, state: RobotState, i: int, r: _Robot) -> None:
        latch = self._pressed(i, r)
        if latch is not None:
            r.phase, r.latch, r.next = BLOCKED, latch, math.inf
        else:
            r.phase, r.speed, r.profile = DRIVE, 0.0, SpeedUp(self.cruise, self.accel)
            r.stall_at, r.touch = math.inf, None
            self._restart_grid(r)
        self._write_contact(state, i, r)

    # -- pickling -----------------------------------------------------------------------------
    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._placed = False  # the engine lost its space: put the robots back before stepping
