"""Nasty worlds and an invariant-checking bounce loop, shared by the adversarial tests.

Imported by name (the folder's conftest puts it on ``sys.path``) so that a fresh interpreter or
a spawned worker process can import it too: the cross-process determinism tests call
`trajectory_digest` there.

Worlds are built on a unit scale and then mapped by ``x -> scale * x + shift`` so that every
shape can be tried from 1e-4 to 1e5 units and a million units away from the origin, where a
double has only ~1e-10 of absolute resolution left.
"""

from __future__ import annotations

import functools
import hashlib
import math

import numpy as np
import shapely

from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.backends.pymunk_dynamic import DEPTH, TOUCH
from bounce_gym.dynamics.platform import PLATFORM_RADIUS
from bounce_gym.dynamics.rules import RULES
from bounce_gym.worlds import World, generators

#: the noise models, in the config form `bounce_gym.dynamics.make_noise` takes; errors of whole
#: 45° bins, so that the cell backend (8 orientation bins by default) takes them too
NOISES = {
    "exact": None,
    "reliable": {"type": "reliable", "r": 0.7, "eps_deg": 45},
    "interval": {"type": "interval", "lo_deg": -45, "hi_deg": 45},
}
RULE_NAMES = sorted(RULES)
#: the motion models under test: "pymunk" is the pymunk backend's exact model (physics="ideal");
#: "dynamic" its physics (physics="dynamic"), see `make_dynamics`
BACKENDS = ("kinematic", "pymunk", "cell")
KINDS = ("star", "rooms", "grid", "corridor", "needles", "holes", "gon2000", "star2000", "comb")
SCALES = (1e-4, 1e-2, 1.0, 1e2, 1e5)
SHIFT = 1e6
#: (scale, shift) of every world tried: each scale at the origin, and the scales from 100 up
#: shifted by 1e6. Smaller maps that far out are not valid worlds today (the area of their
#: rings, or of the thin holes, cancels out: test_world_shifted_far_from_the_origin_keeps_its_area)
#: and their 1e-4 features shrink towards the spacing of doubles there (1.2e-10 at 1e6).
TRANSFORMS = tuple((s, 0.0) for s in SCALES) + tuple((s, SHIFT) for s in SCALES if s >= 100)

#: the width of the thin passages, relative to the map's size
THIN = 1e-4


# -- worlds ---------------------------------------------------------------------------------------
def _corridor() -> tuple[list, list]:
    """Two unit rooms joined by a corridor 1e-4 wide and one unit long."""
    w = THIN * 3.0  # the map is 3 units wide
    lo, hi = 0.5 - w / 2, 0.5 + w / 2
    outer = [(0, 0), (1, 0), (1, lo), (2, lo), (2, 0), (3, 0), (3, 1), (2, 1), (2, hi), (1, hi),
             (1, 1), (0, 1)]
    return outer, []


def _needles() -> tuple[list, list]:
    """A square with 12 needles 1e-4 wide pointing in from the walls and a spike pointing out,
    plus a needle-shaped hole."""
    w = THIN
    outer: list[tuple[float, float]] = [(0, 0)]
    for x in np.linspace(0.1, 0.9, 6):  # needles up from the bottom wall, 0.6 long
        outer += [(x - w / 2, 0), (x, 0.6), (x + w / 2, 0)]
    outer += [(1, 0), (1, 0.5 - w / 2), (1.6, 0.5), (1, 0.5 + w / 2), (1, 1)]  # a spike out
    for x in np.linspace(0.9, 0.1, 6):  # needles down from the top wall
        outer += [(x + w / 2, 1), (x, 0.7), (x - w / 2, 1)]
    outer += [(0, 1)]
    hole = [(0.2, 0.65), (0.8, 0.65 - w), (0.8, 0.65 + w)]
    return outer, [hole]


def _holes() -> tuple[list, list]:
    """A unit square with 64 small holes: squares, triangles and thin slivers."""
    holes = []
    for i in range(8):
        for j in range(8):
            cx, cy, s = (i + 0.5) / 8, (j + 0.5) / 8, 0.03
            k = (i + j) % 3
            if k == 0:
                holes.append([(cx - s, cy - s), (cx + s, cy - s), (cx + s, cy + s),
                              (cx - s, cy + s)])
            elif k == 1:
                holes.append([(cx - s, cy - s), (cx + s, cy - s), (cx, cy + s)])
            else:
                holes.append([(cx - s, cy), (cx + s, cy - THIN), (cx + s, cy + THIN)])
    return [(0, 0), (1, 0), (1, 1), (0, 1)], holes


def _gon(n: int, rng: np.random.Generator | None) -> tuple[list, list]:
    """A regular n-gon, or (with ``rng``) a star-shaped one with random radii in [0.3, 1]."""
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    radii = np.ones(n) if rng is None else rng.uniform(0.3, 1.0, n)
    return np.column_stack((radii * np.cos(angles), radii * np.sin(angles))).tolist(), []


def _comb() -> tuple[list, list]:
    """A comb: 40 teeth gaps 1e-4 wide (slots a robot can enter only head-on)."""
    w = THIN * 2.0
    outer: list[tuple[float, float]] = [(0, 0), (2, 0), (2, 1)]
    for x in np.linspace(1.95, 0.05, 40):  # slots down from the top wall
        outer += [(x + w / 2, 1), (x + w / 2, 1.5), (x - w / 2, 1.5), (x - w / 2, 1)]
    outer += [(0, 1)]
    return outer, []


def unit_world(kind: str, seed: int) -> World:
    """An un-scaled world of ``kind``; ``seed`` drives the random kinds."""
    rng = np.random.default_rng(seed)
    if kind == "star":
        return generators.random_star_polygon(rng, avg_radius=1.0, center=(0.0, 0.0),
                                              irregularity=0.25, spikiness=0.4)
    if kind == "rooms":
        return generators.random_room_tree(rng, n_rooms=5)
    if kind == "grid":
        return generators.random_grid(rng, 12, 12, n_obstacles=8, max_size=3)
    builders = {"corridor": _corridor, "needles": _needles, "holes": _holes, "comb": _comb,
                "gon2000": lambda: _gon(2000, None), "star2000": lambda: _gon(2000, rng)}
    outer, holes = builders[kind]()
    return World(outer, holes, name=kind)


@functools.cache
def make_world(kind: str, seed: int, scale: float, shift: float) -> World:
    """``unit_world(kind, seed)`` mapped by x -> scale * x + shift."""
    base = unit_world(kind, seed)
    return World(base.outer * scale + shift, [h * scale + shift for h in base.holes],
                 name=f"{kind}[x{scale:g}+{shift:g}]")


def grid_cell(kind: str, world: World) -> float:
    """A cell size for the cell backend: the map's own grid for ``grid``, else 1/30 of the
    bounding box (fine enough for several free cells in every nasty shape)."""
    if kind == "grid":
        return (world.bounds[2] - world.bounds[0]) / 12
    return world.diameter / 30


# -- the checked loop ------------------------------------------------------------------------------
def slack(world: World) -> float:
    """The tolerance of the checks: ten times the world's own (relative to its size), and at
    least 64 spacings of doubles at the world's coordinates (which matter a million units out)."""
    magnitude = float(np.abs(world.outer).max())
    return max(10 * world.tol, 64 * float(np.spacing(magnitude)))


def escaped(world: World, points: np.ndarray, radius: float) -> np.ndarray:
    """Robots outside the free space: not in ``World.contains`` with the robot radius, and
    also outside it (or closer to the boundary than ``radius``) by more than `slack`."""
    out = ~world.contains(points, radius)
    if out.any():
        tol = slack(world)
        pts = np.asarray(points)[out]
        dist = world.boundary_distance(pts)
        inside = shapely.contains_xy(world.polygon, pts[:, 0], pts[:, 1])
        out[out] = np.where(inside, dist < radius - tol, dist + radius > tol)
    return out


def sunk(world: World, points: np.ndarray, radius: float, depth: float) -> np.ndarray:
    """Robots of ``physics="dynamic"`` out of the free space: outside the world, or deeper than
    ``depth`` (+ `slack`) into a wall — a rigid-body contact overlaps by a hair
    (`bounce_gym.dynamics.backends.pymunk_dynamic.DEPTH`)."""
    inside = shapely.contains_xy(world.polygon, points[:, 0], points[:, 1])
    return ~inside | (world.boundary_distance(points) < radius - depth - slack(world))


class InvariantError(AssertionError):
    """An invariant failed; the message says which, where and after how many bounces."""


def _finite(state) -> bool:
    return bool(np.isfinite(state.position).all() and np.isfinite(state.heading).all()
                and np.isfinite(state.contact_normal).all() and np.isfinite(state.odometer).all())


def run_checked(kind: str, world: World, backend: str, rule: str, noise: str, radius: float,
                n_bounces: int, seed: int, n_robots: int = 1,
                robot_collisions: str = "ignore", physics: dict | None = None,
                depth: float | None = None) -> dict:
    """Bounce ``n_bounces`` times in ``world`` (built as ``kind``) and check every invariant
    after each bounce (see `checked_loop`). The cell backend steps cells of `grid_cell`; the
    continuous ones drive 1/40 of the map per tick. ``physics``: more physical parameters of
    "dynamic"; ``depth``: see `checked_loop`."""
    step = grid_cell(kind, world) if backend == "cell" else world.diameter / 40
    dyn = make_dynamics(world, backend, rule, noise, radius, step, n_robots, robot_collisions,
                        physics)
    return checked_loop(dyn, n_bounces, seed, depth)


def make_dynamics(world: World, backend: str, rule: str, noise: str, radius: float,
                  step_length: float, n_robots: int = 1,
                  robot_collisions: str = "ignore",
                  physics: dict | None = None) -> BounceDynamics:
    """``backend`` "pymunk" is pymunk's exact model; "dynamic" is pymunk with
    ``physics="dynamic"``, its world scaled so that the robot is a Create 2 (radius 0.17 m):
    the physics is then the same at every scale of the map, and the scales test the numbers.
    ``physics``: more of its physical parameters."""
    if backend == "dynamic":
        return BounceDynamics(world, n_robots, backend="pymunk", rule=rule, noise=NOISES[noise],
                              radius=radius, step_length=step_length,
                              robot_collisions=robot_collisions, physics="dynamic",
                              physics_params={"world_scale": PLATFORM_RADIUS / radius,
                                              **(physics or {})})
    return BounceDynamics(world, n_robots, backend=backend, rule=rule, noise=NOISES[noise],
                          radius=radius, step_length=step_length,
                          robot_collisions=robot_collisions,
                          physics="ideal" if backend == "pymunk" else None)


def angles_for(rule: str, backend: str, rng: np.random.Generator, shape) -> np.ndarray:
    """Random bounce parameters the rule accepts (whole 45° bins on the cell backend)."""
    if backend == "cell":
        return np.radians(45.0 * rng.integers(1, 8, shape))
    if rule == "relative":
        return rng.uniform(0.05, 2 * np.pi - 0.05, shape)
    return rng.uniform(0.05, np.pi - 0.05, shape)


def checked_loop(dyn: BounceDynamics, n_bounces: int, seed: int,
                 depth: float | None = None) -> dict:
    """Reset ``dyn`` with ``seed``, drive to the first contact and bounce ``n_bounces`` times,
    checking after every bounce that every robot stays in the free space (``World.contains``
    with the robot radius; the world's tolerance is relative to its size), the state is finite,
    ``ticks`` rises by exactly what `bounce` returns, bump counts and odometers never fall,
    clocks restart at a bump and otherwise grow by at most the elapsed ticks, headings lie in
    [0, 2π), a blocked robot touches the wall or robot it faces, and colliding disks never
    overlap. ``depth``: how far (in radii) a rigid body of ``physics="dynamic"`` may overlap a
    wall or robot (default: what a contact reaches, below). Returns counters (bounces, escapes = 0,
    non-finite = 0) or raises `InvariantError`."""
    world, backend = dyn.world, dyn.backend
    radius, m = backend.radius, dyn.n_robots
    tol = slack(world)
    touch = 2 * backend.contact_tol + tol
    #: physics="dynamic": rigid bodies in contact overlap by a hair — new contacts by ``DEPTH``
    #: radii, touching ones by ``TOUCH`` times that, a stack's solver residuals a little more
    if not backend.turns_take_time:
        depth = 0.0
    depth = radius * (2 * TOUCH * DEPTH if depth is None else depth)
    state = dyn.reset(np.random.default_rng(seed))
    rng = np.random.default_rng(seed + 1)
    dyn.drive_to_contact()
    params = angles_for(dyn.rule_name, backend.name, rng, (n_bounces, m))

    def fail(what: str, k: int) -> InvariantError:
        return InvariantError(f"{what} after {k} bounces: {backend.name} {dyn.rule_name} "
                         f"{type(dyn.noise).__name__} r={radius:g} in {world.name} (seed {seed}); "
                         f"positions {state.position.tolist()}")

    for k in range(n_bounces):
        ticks0, bumps0 = state.ticks, state.bumps.copy()
        clock0, odo0 = state.clock.copy(), state.odometer.copy()
        elapsed = dyn.bounce(params[k])
        if not _finite(state):
            raise fail("non-finite state", k)
        out = (sunk(world, state.position, radius, depth) if backend.turns_take_time
               else escaped(world, state.position, radius))
        if out.any():
            raise fail("escape from the free space", k)
        if state.ticks - ticks0 != elapsed or elapsed < 1:
            raise fail(f"ticks went {ticks0} -> {state.ticks} but bounce returned {elapsed}", k)
        if np.any(state.bumps < bumps0) or np.any(state.odometer < odo0):
            raise fail("bump count or odometer fell", k)
        if not np.all((state.heading >= 0) & (state.heading < 2 * np.pi)):
            raise fail(f"heading outside [0, 2π): {state.heading.tolist()}", k)
        bumped = state.bumps > bumps0
        if np.any(state.clock[bumped] > elapsed - 1) or np.any(
                (state.clock[~bumped] < clock0[~bumped])
                | (state.clock[~bumped] > clock0[~bumped] + elapsed)):
            raise fail(f"clocks {clock0.tolist()} -> {state.clock.tolist()} in {elapsed} ticks",
                       k)
        # a tick drives step_length; a diagonal king move of the cell grid √2 cells; a rigid
        # body pushed sideways by another one at most √2 cruise speeds (energy), then slows
        reach = backend.step_length * (math.sqrt(2) if backend.name == "cell"
                                       or (backend.turns_take_time and backend.collide) else 1.0)
        if np.any(state.odometer - odo0 > elapsed * reach + touch):
            raise fail("drove further than the ticks allow", k)
        if backend.turns_take_time:  # braked to rest after its bumper fired (or it stalled)
            if np.any(state.blocked & (state.contact_edge < 0) & (state.contact_robot < 0)):
                raise fail("a blocked robot has no bumper contact", k)
        elif backend.name != "cell":
            _check_contacts(dyn, state, radius, touch, tol, fail, k)
        if backend.collide:
            _check_disks(backend, state, radius, fail, k, depth)
    return {"bounces": int(state.bumps.sum()), "escapes": 0, "nonfinite": 0,
            "ticks": int(state.ticks)}


def _check_contacts(dyn, state, radius, touch, tol, fail, k) -> None:
    """A blocked robot touches what it faces: the wall at distance ``radius`` or a robot."""
    world = dyn.world
    blocked = np.flatnonzero(state.blocked)
    at_wall = blocked[state.contact_edge[blocked] >= 0]
    if len(at_wall):
        gap = world.boundary_distance(state.position[at_wall]) - radius
        ahead = world.first_hit(state.position[at_wall], state.direction[at_wall], radius)
        if np.any(np.abs(gap) > touch) or np.any(ahead.distance > touch):
            raise fail(f"blocked robots {at_wall.tolist()} are {gap.tolist()} from the wall, "
                       f"{ahead.distance.tolist()} from the wall ahead", k)
    at_robot = blocked[state.contact_robot[blocked] >= 0]
    if len(at_robot):
        other = state.contact_robot[at_robot]
        dist = np.hypot(*(state.position[at_robot] - state.position[other]).T)
        # the robot it met may drive on until the end of that tick (a bounce step stops at the
        # end of the tick in which the first robot blocks), so at most one step further away
        if np.any(dist > 2 * radius + dyn.backend.step_length + touch):
            raise fail(f"robots {at_robot.tolist()} blocked by robots {other.tolist()} "
                       f"{dist.tolist()} away", k)
    if np.any((state.contact_edge[blocked] < 0) & (state.contact_robot[blocked] < 0)):
        raise fail("a blocked robot touches nothing", k)


def _check_disks(backend, state, radius, fail, k, depth=0.0) -> None:
    """Colliding robots never overlap (disks; rigid bodies by at most ``depth``), or share a
    cell (the grid)."""
    if backend.name == "cell":
        cells = backend.model.cell_of(state.position, state.heading) % backend.model.n_positions
        if len(set(cells.tolist())) < len(cells):
            raise fail("two robots share a cell", k)
        return
    diff = state.position[:, None] - state.position[None]
    dist = np.hypot(diff[..., 0], diff[..., 1])
    np.fill_diagonal(dist, np.inf)
    if dist.min() < 2 * radius - depth - 1e-6 * radius - 10 * backend.world.tol:
        raise fail(f"disks overlap: closest centres {dist.min()} < 2R = {2 * radius}", k)


# -- determinism ----------------------------------------------------------------------------------
def trajectory_digest(rule: str, seed: int, n_bounces: int = 300, backend: str = "kinematic",
                      noise: str = "reliable", n_robots: int = 1) -> str:
    """sha256 of the positions, headings, clocks and ticks of ``n_bounces`` bounces, built from
    ``seed`` alone (nothing is pickled): the same in every process for the same arguments."""
    world = make_world("holes", 0, 100.0, 1e6)
    radius = 0.002 if n_robots > 1 or backend == "dynamic" else 0.0
    dyn = make_dynamics(world, backend, rule, noise, radius, world.diameter / 40, n_robots,
                        "bounce" if n_robots > 1 else "ignore")
    state = dyn.reset(np.random.default_rng(seed))
    dyn.drive_to_contact()
    params = angles_for(rule, backend, np.random.default_rng(seed + 1), (n_bounces, n_robots))
    digest = hashlib.sha256()
    for row in params:
        dyn.bounce(row)
        for array in (state.position, state.heading, state.clock, state.bumps):
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(int(state.ticks).to_bytes(8, "little"))
    return digest.hexdigest()


def scale_label(scale: float) -> str:
    return f"1e{int(round(math.log10(scale)))}"
