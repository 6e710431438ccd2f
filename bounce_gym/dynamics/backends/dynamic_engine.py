"""The pymunk space of ``physics="dynamic"``: disk robots with mass, static walls, contacts.

`DynamicEngine` owns one `pymunk.Space` holding

* the **walls**: one static `pymunk.Segment` (radius 0) per world edge;
* the **robots**: dynamic bodies of mass m and the moment of a uniform disk (m r² / 2), each
  carrying a `pymunk.Circle` of the robot radius. Robots collide with walls and — with
  ``robot_collisions="bounce"`` — with each other.

Its controller (`bounce_gym.dynamics.backends.pymunk_dynamic`) pushes the robots with forces and
torques; the engine's solver resolves every contact, with the restitution e and the Coulomb
friction μ given (each shape carries √e and √μ: pymunk multiplies the two shapes' values).

**Nothing but the bodies carries over from one step to the next.** Chipmunk, the engine under
pymunk, keeps three kinds of hidden state, and each is switched off:

* *Warm starting*: a contact that persists starts the next step's solve from last step's impulse,
  scaled by the ratio of the step lengths. With steps whose length varies by orders of magnitude
  (a free flight of seconds, then contact steps of milliseconds) that scaling throws robots off
  walls, and it is state a rebuilt space lacks. The contact handler zeroes each contact's
  accumulated impulses before the solver runs, so every step solves its contacts from scratch.
* *Position correction*: overlapping shapes are pushed apart by a separate "bias" velocity that
  is spent in the next step, whatever its length. ``collision_bias = 1`` turns it off; the
  stepping rule of the controller keeps overlaps below a tiny depth instead.
* *Order*: the solver visits contacts in the order the broad phase finds them, which depends on
  the history of its bounding-box tree and on shape ids. `canonicalize` removes every robot shape
  and adds it back with the same ids, so that the tree, its cached pairs and therefore the order
  are functions of the bodies alone.

The controller calls `canonicalize` at the start of every drive, so a space rebuilt from the
robot state (after unpickling, which drops the space) continues bit for bit as the original
would have.

The contact handler is the **bump sensor's raw signal**: after a step, `contacts` lists every
robot–wall and robot–robot contact of that step as (robot, kind, index, nx, ny), the normal
pointing from the robot's centre to the contact; the controller decides which of them press the
bumper.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk
from pymunk._chipmunk import lib as _chipmunk

from bounce_gym.worlds import World

#: kinds of contact in `DynamicEngine.contacts`
WALL, ROBOT = 0, 1
_ROBOT_TYPE, _WALL_TYPE = 1, 2
_CAT_WALL, _CAT_ROBOT = 0x1, 0x2


class DynamicEngine:
    """One pymunk space for ``n_robots`` disks of ``radius`` and ``mass`` in ``world``.

    Args:
        world: the walls.
        n_robots: number of robot bodies.
        radius: robot radius in world units (> 0).
        mass: robot mass.
        restitution: coefficient of restitution of every contact.
        friction: friction coefficient of every contact.
        iterations: solver iterations per step.
        collide: whether robots collide with each other.
    """

    def __init__(self, world: World, n_robots: int, radius: float, mass: float,
                 restitution: float, friction: float, iterations: int, collide: bool) -> None:
        self.world = world
        self.n_robots = n_robots
        self.radius = radius
        self.mass = mass
        self.moment = 0.5 * mass * radius * radius
        self.restitution = restitution
        self.friction = friction
        self.iterations = iterations
        self.collide = collide
        self._space: pymunk.Space | None = None
        #: contacts of the last step: (robot, WALL or ROBOT, edge or robot, nx, ny)
        self.contacts: list[tuple[int, int, int, float, float]] = []
        #: `contacts` and its entries by robot (`contacts_of`)
        self._grouped: tuple[list, dict[int, list]] = (self.contacts, {})

    # -- the space ----------------------------------------------------------------------------
    @property
    def space(self) -> pymunk.Space:
        if self._space is None:
            self._build()
        return self._space

    def _build(self) -> None:
        space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 1.0
        space.iterations = self.iterations
        space.collision_bias = 1.0  # no position correction: see the module docstring
        space.collision_slop = 0.0
        elasticity, friction = math.sqrt(self.restitution), math.sqrt(self.friction)
        wall_filter = pymunk.ShapeFilter(categories=_CAT_WALL, mask=_CAT_ROBOT)
        edge_of: dict[pymunk.Shape, int] = {}
        for k, (a, b) in enumerate(zip(self.world.edge_start.tolist(),
                                       self.world.edge_end.tolist(), strict=True)):
            wall = pymunk.Segment(space.static_body, tuple(a), tuple(b), 0.0)
            wall.collision_type = _WALL_TYPE
            wall.filter = wall_filter
            wall.elasticity, wall.friction = elasticity, friction
            edge_of[wall] = k
        space.add(*edge_of)
        self._id_base = _chipmunk.cpSpaceGetShapeIDCounter(space._space)
        mask = _CAT_WALL | (_CAT_ROBOT if self.collide else 0)
        robot_filter = pymunk.ShapeFilter(categories=_CAT_ROBOT, mask=mask)
        bodies, disks = [], []
        for _ in range(self.n_robots):
            body = pymunk.Body(self.mass, self.moment)
            disk = pymunk.Circle(body, self.radius)
            disk.collision_type = _ROBOT_TYPE
            disk.filter = robot_filter
            disk.elasticity, disk.friction = elasticity, friction
            bodies.append(body)
            disks.append(disk)
        space.add(*bodies, *disks)
        space.on_collision(_ROBOT_TYPE, _WALL_TYPE, pre_solve=self._on_contact)
        if self.collide:
            space.on_collision(_ROBOT_TYPE, _ROBOT_TYPE, pre_solve=self._on_contact)
        # Chipmunk's shapes and bodies, as the contact handler and the body accessors see them
        self._edge_of = {wall._shape: k for wall, k in edge_of.items()}
        self._robot_of = {disk._shape: i for i, disk in enumerate(disks)}
        self._bodies = bodies
        self._cp_bodies = [body._body for body in bodies]
        self._cp_space = space._space
        self._cp_disks = [disk._shape for disk in disks]
        self._space = space

    def canonicalize(self) -> None:
        """Remove every robot shape and add it back, with the ids it had when the space was
        built: the broad phase then depends on the bodies only (see the module docstring).
        Chipmunk's own calls, those of pymunk's `Space.remove` and `Space.add`, whose
        bookkeeping (which shapes the space holds) the round trip leaves as it was."""
        self.space  # noqa: B018  (builds the space on first use)
        space, disks = self._cp_space, self._cp_disks
        for disk in disks:
            _chipmunk.cpSpaceRemoveShape(space, disk)
        _chipmunk.cpSpaceSetShapeIDCounter(space, self._id_base)
        for disk in disks:
            _chipmunk.cpSpaceAddShape(space, disk)

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        for key in ("_space", "_edge_of", "_robot_of", "_bodies", "_cp_bodies", "_cp_space",
                    "_cp_disks", "_id_base"):
            state.pop(key, None)
        state["_space"] = None
        return state

    # -- bodies -------------------------------------------------------------------------------
    def set_bodies(self, position: np.ndarray, angle: np.ndarray, velocity: np.ndarray,
                   omega: np.ndarray) -> None:
        """Place every body: position (m, 2), unwrapped angle (m,), velocity (m, 2), angular
        velocity (m,)."""
        self.space  # noqa: B018  (builds the space on first use)
        for i, body in enumerate(self._bodies):
            body.position = (float(position[i, 0]), float(position[i, 1]))
            body.angle = float(angle[i])
            body.velocity = (float(velocity[i, 0]), float(velocity[i, 1]))
            body.angular_velocity = float(omega[i])

    def read(self) -> list[tuple[float, float, float, float, float, float]]:
        """Every body as (x, y, unwrapped angle, vx, vy, angular velocity)."""
        out = []
        for body in self._cp_bodies:
            p, v = _chipmunk.cpBodyGetPosition(body), _chipmunk.cpBodyGetVelocity(body)
            out.append((p.x, p.y, _chipmunk.cpBodyGetAngle(body), v.x, v.y,
                        _chipmunk.cpBodyGetAngularVelocity(body)))
        return out

    def set_velocity(self, i: int, vx: float, vy: float, w: float) -> None:
        """Set robot ``i``'s velocity and angular velocity (the motors' impulse)."""
        body = self._cp_bodies[i]
        _chipmunk.cpBodySetVelocity(body, (vx, vy))
        _chipmunk.cpBodySetAngularVelocity(body, w)

    def push(self, i: int, fx: float, fy: float, torque: float) -> None:
        """Force (fx, fy) and torque of robot ``i`` for the next step (cleared by the step)."""
        body = self._cp_bodies[i]
        _chipmunk.cpBodySetForce(body, (fx, fy))
        _chipmunk.cpBodySetTorque(body, torque)

    def step(self, dt: float) -> list[tuple[int, int, int, float, float]]:
        """Advance the space by ``dt`` seconds; returns `contacts`. Calls Chipmunk's step
        directly: pymunk's wrapper only defers what callbacks add or remove, which the contact
        handler never does."""
        self.space  # noqa: B018  (builds the space on first use)
        self.contacts = []
        _chipmunk.cpSpaceStep(self._cp_space, dt)
        return self.contacts

    def contacts_of(self, robot: int) -> list[tuple[int, int, int, float, float]]:
        """The entries of `contacts` of one robot, in their order (grouped once per step)."""
        if self._grouped[0] is not self.contacts:
            groups: dict[int, list] = {}
            for contact in self.contacts:
                groups.setdefault(contact[0], []).append(contact)
            self._grouped = (self.contacts, groups)
        return self._grouped[1].get(robot, [])

    # -- the contact handler ------------------------------------------------------------------
    def _on_contact(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        """Record the contact for the bump sensor, and zero the impulses it carries over from
        the last step (warm starting) before the solver uses them. Reads Chipmunk's arbiter
        (shapes a and b, normal from a to b) directly: pymunk has no setter for the impulses
        (its own pickling writes them) and its wrappers cost more than the step."""
        arb = arbiter._arbiter
        contacts = arb.contacts
        for k in range(arb.count):
            contact = contacts[k]
            contact.jnAcc = 0.0
            contact.jtAcc = 0.0
        n = arb.n
        robot = self._robot_of.get(arb.a)
        if robot is None:  # a is the wall
            other, robot, nx, ny = arb.a, self._robot_of[arb.b], -n.x, -n.y
        else:
            other, nx, ny = arb.b, n.x, n.y
        edge = self._edge_of.get(other)
        if edge is not None:
            self.contacts.append((robot, WALL, edge, nx, ny))
        else:
            j = self._robot_of[other]
            self.contacts.append((robot, ROBOT, j, nx, ny))
            self.contacts.append((j, ROBOT, robot, -nx, -ny))
