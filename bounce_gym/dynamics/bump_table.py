"""A tabulated bump-to-bump map of ``physics="dynamic"``: the simulator's drives, run once.

Moving particles through the simulator (`bounce_gym.dynamics.bump_sampler.simulate_bumps`)
costs about a millisecond per robot and bump on pymunk's dynamic physics, seconds per update
for 10⁴ particles. But between two bumps a robot does only two things that matter
(`bounce_gym.dynamics.backends.pymunk_dynamic`): it turns in place by the executed rotation —
a timed turn, whose duration depends on the rotation alone — and, from rest at a tick boundary,
drives along its new heading ψ until it is blocked again. The drive depends only on where on
the boundary it starts and on ψ, not on the rule's angle, the noise or the clock. So the drive
is tabulated once, as a function on the Poincaré section of the motion at the boundary, in
Birkhoff's coordinates of billiards — arc length s along the configuration-space boundary
(`bounce_gym.dynamics.boundary_pieces`) and the heading ψ — and the noise, the rule's angle and
the turn are applied at lookup time. Tabulating a map once over a grid of its domain and reading
it afterwards is the idea of Hsu's cell-to-cell mapping (C. S. Hsu, *Cell-to-Cell Mapping*,
Springer 1987, ch. 1–2); here the grid points keep continuous images and are interpolated.

**The table.** Nodes at ``spacing`` robot radii along every piece (both ends included) ×
``headings`` headings ψ = 2π j / headings. Each node's robot is placed at rest at the boundary point (moved a
hair into the free space, as `bump_sampler` places section points: `INSET`, `CHORD_SAG`) with
heading ψ and driven by the real simulator to its first contact (`drive_from_rest`, many robots
per space, ``robot_collisions="ignore"``). A node keeps: the contact point, the heading there
(minus ψ), the contact normal, the piece it lies on, and the drive's duration in seconds. A node
whose robot reads its bumper where it was placed (ψ faces the wall) *stays*: the next bump is
at the same pose, after no drive. The duration comes from a simulator run with ticks of
``step_length / TICK_SPLIT``, which brackets it within a quarter tick; within the bracket it is
the odometer's distance at cruise speed plus the start-and-stop lag (the median over all nodes).
Its whole ticks are exact at the nodes, since the drive starts at a tick boundary.

**Lookup** (`BumpTable.bumps`, vectorised). The executed rotation is ``angles[action] mod 2π``
plus a draw of the dynamics' noise model (Alam's relative rule, as the simulator executes it);
ψ = heading + rotation; the contact point is projected onto the boundary (piece, s). A robot
that touches a wall ahead of ψ bumps again where it is (its bumper reads the walls it touches,
within `TOUCH`). Otherwise the drive is interpolated bilinearly in (s, ψ) between the four nodes
around it where all four end on the same piece with durations within `CLOSE` ticks of each other
(the map is smooth there) — the end as a point of that piece, its arc length and its offset
along the normal interpolated (a straight line between ends on both sides of an obstacle's
rounded corner would cut into the obstacle, where no later lookup finds a contact), on a
ring's seam not at all; elsewhere — across the corner a drive's target jumps at, or between a
drive and a stay — the robot drives straight to the contact ahead, cast with `World.first_hit`
(a swept disk), taking the distance's time at cruise speed plus the lag (`BumpTable.drives`).
The clock at the next bump is the turn's ticks plus the drive's: the turn, started at the
bump tick, ends after ``Turn.duration`` seconds (`bounce_gym.dynamics.profiles`), the robot waits
for the next tick boundary and the bump tick itself is not counted, so it adds
``max(ceil(duration / τ), 1) − 1`` ticks; the drive adds ``ceil(seconds / τ)``.

**Reset drives** (`BumpTable.reset_drives`): a robot at rest at an interior pose drives the
same line as a robot started from the boundary point behind it (cast back along −ψ with the
world's swept-disk raycast, `World.first_hit`), from rest too, so it arrives ``b / v`` seconds
earlier, b the distance behind.

**Cache.** A table depends on the world, the backend and its physics parameters, the robot's
radius, the step length, the rule and the resolution — not on the noise, Φ or the cell model —
and is stored like the sampled GCM (`bounce_gym.model_cache`: ``<fingerprint>.npz``, written
atomically, read as data, rebuilt with a warning when unusable, built once when processes ask
for it at once), in ``<cache>/bump_tables`` (``$BOUNCE_GYM_CACHE`` or ``<home>/cache``). The
tables of the shipped evaluations' dynamic-physics experiments come with the package
(`SHIPPED_TABLES`, compressed) and are read before that folder, so a fresh install builds none
for them; any other table is built once per cache folder.

Usage — the factory picks the table where it applies (pymunk's dynamic physics, the relative
rule; continuous headings) and the simulator otherwise::

    motion = bump_motion(model, dynamics)           # dynamics: BounceDynamics kwargs + world
    state, end, heading, clock = motion.reset_drives(point, heading, rng, max_ticks)
    outcomes = motion.bumps(angles, action, end, heading, rng, max_ticks)   # a BumpOutcomes

The measured error against the simulator, and the build times, are in
docs/bump_table.md; `table_error` computes them.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from bounce_gym import model_cache
from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.dynamics.backends.pymunk_dynamic import ARC_MARGIN, DEPTH, TRAVEL
from bounce_gym.dynamics.boundary_pieces import BoundaryPieces
from bounce_gym.dynamics.bump_sampler import (
    CHORD_SAG,
    INSET,
    default_max_ticks,
    drive_from_rest,
    reset_drives,
    simulate_bumps,
)
from bounce_gym.dynamics.noise import Exact, make_noise
from bounce_gym.dynamics.platform import PhysicsParams, physics_params
from bounce_gym.dynamics.profiles import Turn
from bounce_gym.dynamics.rules import TWO_PI
from bounce_gym.dynamics.segment_grid import SegmentGrid
from bounce_gym.errors import ConfigError

#: the version of the stored layout and of the construction; a change invalidates old files
FORMAT = 2
#: default node spacing along the boundary, in robot radii (8.5 cm on a Create 2), and number
#: of tabulated headings (3° apart): chosen from the measured error and build time
#: (docs/bump_table.md)
DEFAULT_SPACING = 0.5
DEFAULT_HEADINGS = 120
#: the build simulates with ticks this many times shorter: the drive's duration is known within
#: 1 / TICK_SPLIT of a tick before the odometer refines it
TICK_SPLIT = 4
#: the four nodes around a lookup are interpolated when their drives end on one piece and their
#: durations differ by at most this many ticks
CLOSE = 1.0
#: a pose farther than this (in robot radii) from the boundary is not a contact: the bumper's
#: travel (`pymunk_dynamic.TRAVEL`) plus the chords' sag
GAP = TRAVEL + CHORD_SAG
#: a robot whose centre is within (1 + TOUCH) radii of a wall touches it: the dynamic backend's
#: contact depth (`pymunk_dynamic.DEPTH`); a robot that braked off a wall corner and rests a
#: fraction of a millimetre clear of it does not, and drives on when it faces it
TOUCH = DEPTH
#: ``end_piece`` codes of a node: its robot got nowhere within the limit, or stayed blocked
LOST, STAYS = -1, -2
#: the largest rotation whose turn ticks are tabulated (radians): two turns, beyond any noise
MAX_ROTATION = 4 * math.pi
_ARRAYS = ("end", "heading", "normal", "end_piece", "seconds")
#: the tables that ship with the package (package data, ``<fingerprint>.npz``, compressed), read
#: before the cache folder: those of the shipped evaluations' dynamic-physics experiments, so
#: that these build none on a fresh install (`bounce_gym_experiments.shipped_tables` writes them)
SHIPPED_TABLES = Path(__file__).parent / "tables"
#: tables kept in memory per process, by cache file and its version (a planner asks for its
#: table at every episode's reset; reading and checking a file costs a second on a large map)
LOADED_TABLES = 4
_LOADED: dict[Path, tuple[tuple[int, int, int] | None, BumpTable]] = {}


def table_applies(dynamics: dict) -> bool:
    """Whether the dynamics is one the table reproduces: pymunk's dynamic physics (its default)
    with Alam's relative rule."""
    options = dict(dynamics.get("backend_options") or {})
    physics = dynamics.get("physics", options.get("physics"))
    return (dynamics.get("backend", "kinematic") == "pymunk" and physics in (None, "dynamic")
            and dynamics.get("rule", "relative") == "relative")


def dynamic_params(dynamics: dict) -> PhysicsParams:
    """The physical parameters of ``dynamics`` (given directly or in ``backend_options``)."""
    options = dict(dynamics.get("backend_options") or {})
    return physics_params(dynamics.get("physics_params", options.get("physics_params")))


@dataclass(frozen=True)
class BumpTable:
    """The tabulated drives (module docstring). Node ``offset[p] + k · headings + j`` is node k
    of piece p with heading 2π j / headings.

    Attributes:
        pieces: the boundary the nodes lie on.
        walls: the world's edges near each point (the walls a robot may touch).
        intervals: (P,) node intervals per piece (nodes: intervals + 1).
        offset: (P,) the first node of every piece.
        headings: tabulated headings per boundary node.
        end, heading, normal: (nodes, 2) contact points; (nodes,) headings there minus ψ and
            angles of the contact normals.
        end_piece: (nodes,) the piece of the contact; `LOST` or `STAYS`.
        seconds: (nodes,) the drive's duration (0 for a stay).
        tick_seconds: τ, seconds per tick.
        cruise: the cruise speed, world units per second.
        front: the bumper's reach: a contact whose direction makes a cosine above this with
            the heading presses it.
        lag: seconds a drive takes beyond its distance at cruise speed (starting and
            stopping), the median over the nodes.
        turn_steps: the rotations (radians, ascending) above which a turn takes one more tick.
        build_seconds: how long the build took.
        fingerprint: the cache key.
    """

    pieces: BoundaryPieces
    walls: SegmentGrid
    intervals: np.ndarray
    offset: np.ndarray
    headings: int
    end: np.ndarray
    heading: np.ndarray
    normal: np.ndarray
    end_piece: np.ndarray
    seconds: np.ndarray
    tick_seconds: float
    cruise: float
    front: float
    lag: float
    turn_steps: np.ndarray
    build_seconds: float
    fingerprint: str

    @cached_property
    def _end_section(self) -> tuple[np.ndarray, np.ndarray]:
        """Each node's end on the boundary: its arc length along its end piece and its offset
        along the inward normal there (0 for nodes that end nowhere)."""
        along, off = np.zeros(self.n_nodes), np.zeros(self.n_nodes)
        ended = np.flatnonzero(self.end_piece >= 0)
        near = self.pieces.project(self.end[ended])
        point, normal = self.pieces.locate(self.end_piece[ended], near.s)
        along[ended] = near.s
        off[ended] = np.einsum("nc,nc->n", self.end[ended] - point, normal)
        return along, off

    @property
    def n_nodes(self) -> int:
        return len(self.seconds)

    @property
    def nbytes(self) -> int:
        """The size of the tabulated arrays."""
        return sum(getattr(self, name).nbytes for name in _ARRAYS)

    def turn_ticks(self, rotation: np.ndarray) -> np.ndarray:
        """Ticks on the clock a turn by ``rotation`` (radians, either sign) adds (module
        docstring)."""
        return np.searchsorted(self.turn_steps, np.abs(rotation), side="left")

    def drive_ticks(self, seconds: np.ndarray) -> np.ndarray:
        """Ticks on the clock a drive of ``seconds`` from a tick boundary adds."""
        return np.ceil(seconds / self.tick_seconds - 1e-9).astype(np.int64)

    def drives(self, point: np.ndarray, psi: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                          np.ndarray]:
        """Robots at rest at contact points (n, 2) drive along the headings ``psi`` (n,): where
        they are blocked next, their headings and contact normals (n, 2) there, the drives'
        seconds, the pieces they end on (`LOST`, `STAYS`), and whether each point is a contact
        (within `GAP` of the boundary).

        A robot that touches a wall ahead (`TOUCH`: its bumper reads the walls it touches)
        stays. The others are interpolated from the four nodes around them where those agree
        (module docstring). Where they do not — the drive's target jumps between them, or a
        node stays while the robot, a hair clear of the wall, drives — the robot drives straight
        to the contact ahead, cast with `World.first_hit` (a swept disk), in the distance's time
        at cruise speed plus the lag: exact but for the slide along a wall met at a glancing
        angle (up to v² / 2a, 6 cm on a Create 2). Interpolating only the nodes that end on the
        cast contact's piece was measured worse: on the generated grid map their spread over
        3° of heading, up to 0.8 m at 12 m, put 10 % of the reset drives 20 cm off or more."""
        point = np.asarray(point, dtype=np.float64).reshape(-1, 2)
        psi = np.mod(np.asarray(psi, dtype=np.float64), TWO_PI)
        direction = np.column_stack((np.cos(psi), np.sin(psi)))
        radius = self.pieces.radius
        near = self.pieces.project(point)
        contact = np.isfinite(point).all(axis=1) & (near.distance <= GAP * radius)
        piece = np.where(contact, near.piece, 0)
        n_int = self.intervals[piece]
        kf = np.nan_to_num(near.s) / self.pieces.length[piece] * n_int
        k0 = np.clip(np.floor(kf), 0, n_int - 1).astype(np.int64)
        fk = np.clip(kf - k0, 0.0, 1.0)
        jf = psi / TWO_PI * self.headings
        j0 = np.floor(jf).astype(np.int64) % self.headings
        fj = jf - np.floor(jf)
        j1 = (j0 + 1) % self.headings
        base = self.offset[piece]
        corners = np.stack([base + k * self.headings + j for k, j in
                            ((k0, j0), (k0 + 1, j0), (k0, j1), (k0 + 1, j1))])
        weight = np.stack([(1 - fk) * (1 - fj), fk * (1 - fj), (1 - fk) * fj, fk * fj])
        ends, seconds = self.end_piece[corners], self.seconds[corners]
        smooth = ((ends == ends[0]).all(axis=0) & (ends[0] >= 0)
                  & (seconds.max(axis=0) - seconds.min(axis=0) <= CLOSE * self.tick_seconds))
        along, off = self._end_section
        s_c = along[corners]
        smooth &= s_c.max(axis=0) - s_c.min(axis=0) <= 0.5 * self.pieces.length[
            np.maximum(ends[0], 0)]  # not across a ring's seam
        nearest = corners[np.argmax(weight, axis=0), np.arange(len(psi))]
        status = np.where(smooth, ends[0], self.end_piece[nearest])
        end = self.end[nearest]
        angle = self.normal[nearest]
        normal = np.column_stack((np.cos(angle), np.sin(angle)))
        # the nodes' ends interpolated along the boundary (arc length, and offset along the
        # normal): a straight line between ends on both sides of a corner would cut into it
        at, at_normal = self.pieces.locate(ends[0, smooth], np.einsum(
            "cn,cn->n", weight[:, smooth], s_c[:, smooth]))
        end[smooth] = at + np.einsum("cn,cn->n", weight[:, smooth],
                                     off[corners[:, smooth]])[:, None] * at_normal
        normal[smooth] = at_normal
        turned = np.where(smooth, np.einsum("cn,cn->n", weight, self.heading[corners]),
                          self.heading[nearest])
        duration = np.where(smooth, np.einsum("cn,cn->n", weight, seconds), self.seconds[nearest])
        stays, latched = np.zeros(len(point), dtype=bool), near.normal.copy()
        stays[contact], latched[contact] = _touched_ahead(
            self.walls, point[contact], direction[contact], (1 + TOUCH) * radius, self.front)
        # where the nodes disagree, the robot drives straight to the wall ahead: its contact
        # is cast, and the drive takes the distance at cruise speed plus the lag
        rough = np.flatnonzero(contact & ~stays & ~smooth)
        if len(rough):
            hit = self.pieces.world.first_hit(point[rough], direction[rough], radius)
            reach = np.where(np.isfinite(hit.distance), hit.distance, 0.0)
            end[rough] = point[rough] + reach[:, None] * direction[rough]
            normal[rough], turned[rough] = hit.normal, 0.0
            duration[rough] = reach / self.cruise + self.lag
            status[rough] = np.where(np.isfinite(hit.distance),
                                     self.pieces.project(end[rough]).piece, LOST)
        end[stays], normal[stays], turned[stays], duration[stays] = (
            point[stays], latched[stays], 0.0, 0.0)
        status[stays] = STAYS
        return end, np.mod(psi + turned, TWO_PI), normal, duration, status, contact

    def bumps(self, model: CellModel, angles: np.ndarray, action: np.ndarray,
              point: np.ndarray, heading: np.ndarray, rng: np.random.Generator, noise: object,
              max_ticks: int) -> BumpOutcomes:
        """As `bump_sampler.simulate_bumps`, from the table: robots at bump poses bump with
        ``angles[action]`` (plus a draw of ``noise`` each, from ``rng``) and drive to their next
        bump. A pose that is not a contact keeps its place (next state −1, no ticks), as does
        a robot not blocked again within ``max_ticks``."""
        angles = np.asarray(angles, dtype=np.float64).reshape(-1)
        action = np.asarray(action, dtype=np.int64).reshape(-1)
        point = np.asarray(point, dtype=np.float64).reshape(-1, 2)
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        rotation = np.mod(angles[action], TWO_PI)
        noise = make_noise(noise)
        if not isinstance(noise, Exact):
            rotation = rotation + noise.sample(len(rotation), rng)
        end, final, normal, duration, status, contact = self.drives(point, heading + rotation)
        ticks = self.turn_ticks(rotation) + self.drive_ticks(duration)
        states = BumpStates(model)
        arrived = contact & (status != LOST) & (ticks < max_ticks)
        nxt = np.where(arrived, states.of(end, final, normal), -1)
        end = np.where(arrived[:, None], end, point)
        ticks = np.where(arrived, ticks, 0)
        state = np.maximum(states.of(point, heading, np.zeros_like(point)), 0)
        return BumpOutcomes(model.n_cells, angles, state, action, nxt, ticks, point.copy(),
                            end, final)

    def reset_drives(self, model: CellModel, point: np.ndarray, heading: np.ndarray,
                     max_ticks: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """As `bump_sampler.reset_drives`, from the table: robots at rest at interior poses
        drive to their first contact (module docstring): decision states (−1: none within
        ``max_ticks``), contact points, headings and clocks."""
        point = np.asarray(point, dtype=np.float64).reshape(-1, 2)
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        world, radius = self.pieces.world, self.pieces.radius
        direction = np.column_stack((np.cos(heading), np.sin(heading)))
        behind = world.first_hit(point, -direction, radius).distance
        behind = np.where(np.isfinite(behind), behind, 0.0)
        start = point - behind[:, None] * direction
        end, final, normal, duration, status, contact = self.drives(start, heading)
        duration = duration - behind / self.cruise
        # a robot placed with a wall within its bumper's travel ahead is blocked at once
        placed, latched = _touched_ahead(self.walls, point, direction, (1 + TRAVEL) * radius,
                                         self.front)
        end[placed], final[placed], duration[placed] = point[placed], heading[placed], 0.0
        normal[placed] = latched[placed]
        ticks = np.where(duration > 0, self.drive_ticks(np.maximum(duration, 0.0)), 0)
        arrived = placed | (contact & (status >= 0) & (ticks < max_ticks))
        z = np.where(arrived, BumpStates(model).of(end, final, normal), -1)
        return z, end, final, ticks


def _touched_ahead(walls: SegmentGrid, point: np.ndarray, direction: np.ndarray,
                   reach: float, front: float) -> tuple[np.ndarray, np.ndarray]:
    """Whether a wall within ``reach`` of each robot centre lies ahead of it — the direction to
    its nearest point makes a cosine above ``front`` with the heading: the bumper read of a
    robot at rest, as the dynamic backend reads it —, and the normal (towards the robot) of
    the most frontal such wall. ``walls`` lists the world's edges near each point."""
    away, dist, _ = walls.closest(point, walls.near(point))
    ahead = -np.einsum("nkc,nc->nk", away, direction) / np.maximum(dist, 1e-300)
    ahead = np.where(dist <= reach, ahead, -np.inf)
    best = np.argmax(ahead, axis=1) if len(point) else np.zeros(0, dtype=np.int64)
    rows = np.arange(len(point))
    normal = away[rows, best] / np.maximum(dist[rows, best], 1e-300)[:, None]
    return ahead[rows, best] > front, normal


def table_fingerprint(dynamics: dict, spacing: float, headings: int) -> str:
    """The sha256 (hex) of everything a table depends on (module docstring: not the noise)."""
    described = {
        "format": FORMAT, "split": TICK_SPLIT, "world": dynamics["world"].to_dict(),
        "radius": float.hex(float(dynamics.get("radius", 0.0))),
        "step_length": float.hex(float(dynamics.get("step_length", 1.0))),
        "params": repr(dynamic_params(dynamics)), "rule": dynamics.get("rule", "relative"),
        "spacing": float.hex(float(spacing)), "headings": int(headings),
    }
    return hashlib.sha256(json.dumps(described, sort_keys=True).encode()).hexdigest()


def _check_table_arguments(dynamics: dict, spacing: float, headings: int) -> None:
    if not table_applies(dynamics):
        raise ConfigError("bump table: only pymunk's dynamic physics with the relative rule is "
                          "tabulated")
    if not (isinstance(headings, int) and headings >= 4) or not spacing > 0:
        raise ConfigError(f"bump table: expected spacing > 0 and headings >= 4, got {spacing!r}, "
                          f"{headings!r}")


def bump_table(dynamics: dict, spacing: float = DEFAULT_SPACING,
               headings: int = DEFAULT_HEADINGS, cache: Path | str | bool | None = None
               ) -> BumpTable:
    """The table of ``dynamics`` (`BounceDynamics` arguments with the ``world``), from the cache
    or built (module docstring). ``spacing``: node spacing along the boundary in robot radii;
    ``headings``: tabulated headings; ``cache``: a folder, None for the default one (and the
    package's own tables first, `SHIPPED_TABLES`), False for none."""
    _check_table_arguments(dynamics, spacing, headings)
    key = table_fingerprint(dynamics, spacing, headings)
    if cache is False:
        return _build(dynamics, spacing, headings, key)
    default = cache in (None, True)
    folder = model_cache.cache_folder("bump_tables") if default else cache
    path = (Path(folder) / f"{key}.npz").resolve()
    files = (SHIPPED_TABLES / f"{key}.npz", path) if default else (path,)
    signature, table = _LOADED.pop(path, (None, None))
    if table is None or signature != _file_signature(path):

        def load() -> BumpTable | None:
            for file in files:
                stored = model_cache.load_cached(file, FORMAT, key)
                found = None if stored is None else _from_stored(dynamics, spacing, headings,
                                                                 key, *stored, file)
                if found is not None:
                    return found
            return None

        def build() -> BumpTable:
            built = _build(dynamics, spacing, headings, key)
            header = {"format": FORMAT, "fingerprint": key, "build_seconds": built.build_seconds,
                      "lag": built.lag}
            model_cache.store(path, header, {name: getattr(built, name) for name in _ARRAYS})
            return built

        table = model_cache.cached(path, load, build)
    _LOADED[path] = (_file_signature(path), table)  # the most recently used last
    while len(_LOADED) > LOADED_TABLES:
        _LOADED.pop(next(iter(_LOADED)))
    return table


def _file_signature(path: Path) -> tuple[int, int, int] | None:
    """What tells a cache file's versions apart (inode, size, modification time), None
    without one."""
    try:
        stat = path.stat()
    except OSError:
        return None
    return stat.st_ino, stat.st_size, stat.st_mtime_ns


def _layout(dynamics: dict, spacing: float, headings: int, key: str
            ) -> tuple[BoundaryPieces, np.ndarray, np.ndarray, dict]:
    """The boundary, the node intervals and first nodes of its pieces, and the rest of the
    table's fields that follow from the dynamics."""
    radius = float(dynamics.get("radius", 0.0))
    pieces = BoundaryPieces(dynamics["world"], radius)
    intervals = np.maximum(np.ceil(pieces.length / (spacing * radius)), 1).astype(np.int64)
    offset = np.concatenate(([0], np.cumsum((intervals + 1) * headings)[:-1]))
    params = dynamic_params(dynamics)
    tau = params.tick_seconds(float(dynamics.get("step_length", 1.0)))
    walls = SegmentGrid(dynamics["world"].edge_start, dynamics["world"].edge_end, radius,
                        (1 + TRAVEL) * radius)
    fields = {"walls": walls, "headings": headings, "tick_seconds": tau,
              "cruise": params.cruise_speed / params.world_scale,
              "front": math.cos(math.radians(params.bumper_arc) / 2) + ARC_MARGIN,
              "turn_steps": turn_tick_steps(params, tau), "fingerprint": key}
    return pieces, intervals, offset, fields


def _build(dynamics: dict, spacing: float, headings: int, key: str) -> BumpTable:
    began = time.perf_counter()
    pieces, intervals, offset, fields = _layout(dynamics, spacing, headings, key)
    world, radius = pieces.world, pieces.radius
    piece = np.repeat(np.arange(pieces.n_pieces), intervals + 1)
    k = np.arange(len(piece)) - np.repeat(np.cumsum(intervals + 1) - (intervals + 1),
                                          intervals + 1)
    point, normal = pieces.locate(piece, k * pieces.length[piece] / intervals[piece])
    point = point + INSET * world.tol * normal  # as bump_sampler places section points
    outside = ~world.contains(point, radius)
    point[outside] += CHORD_SAG * radius * normal[outside]
    psi = np.arange(headings) * TWO_PI / headings
    fine = dict(dynamics, step_length=float(dynamics.get("step_length", 1.0)) / TICK_SPLIT)
    out = drive_from_rest(fine, np.repeat(point, headings, axis=0), np.tile(psi, len(point)),
                          np.random.default_rng(0), default_max_ticks(fine))
    heading = np.mod(out.heading - np.tile(psi, len(point)) + math.pi, TWO_PI) - math.pi
    end_piece = np.where(out.clock == 0, STAYS, pieces.project(out.end).piece)
    end_piece = np.where(out.blocked, end_piece, LOST)
    seconds, lag = _durations(out.clock, out.odometer, fields["tick_seconds"] / TICK_SPLIT,
                              fields["cruise"], end_piece >= 0)
    arrays = {"end": out.end, "heading": heading,
              "normal": np.arctan2(out.normal[:, 1], out.normal[:, 0]),
              "end_piece": end_piece.astype(np.int32), "seconds": seconds}
    return BumpTable(pieces=pieces, intervals=intervals, offset=offset, end=arrays["end"], heading=arrays["heading"],
                     normal=arrays["normal"], end_piece=arrays["end_piece"],
                     seconds=arrays["seconds"], build_seconds=time.perf_counter() - began,
                     lag=lag, **fields)


def _durations(clock: np.ndarray, odometer: np.ndarray, fine_tick: float, cruise: float,
               drove: np.ndarray) -> tuple[np.ndarray, float]:
    """Each drive's duration: within the bracket (clock − 1, clock] fine ticks the simulator
    gives, the distance at cruise speed plus the start-and-stop lag. 0 for drives that did not
    happen, inf for lost ones; and the lag.

    Each drive's bracket less its distance's time brackets its lag; the lag is the middle of
    the values the most brackets hold (the middles of the brackets are biased: measured with
    1/64 ticks on lab A, the true lag's median is 0.49 s, the middles' 0.59 s)."""
    top = clock * fine_tick
    out = np.where(clock == 0, 0.0, np.inf)
    if not drove.any():
        return out, 0.0
    high = np.sort(top[drove] - odometer[drove] / cruise)
    low = high - fine_tick
    grid = np.linspace(np.percentile(low, 1), np.percentile(high, 99), 4001)
    cover = np.searchsorted(low, grid, side="left") - np.searchsorted(high, grid, side="left")
    best = grid[cover == cover.max()]
    lag = float(0.5 * (best.min() + best.max()))
    estimate = np.clip(odometer / cruise + lag, top - fine_tick * (1 - 1e-6), top)
    return np.where(drove, estimate, out), lag


def turn_tick_steps(params: PhysicsParams, tau: float) -> np.ndarray:
    """The rotations (radians, ascending) at which a turn's duration reaches 1, 2, … ticks of
    ``tau`` seconds (bisection on `Turn.duration`): a turn by up to the first adds no tick to
    the clock, one up to the second adds one, … (module docstring)."""
    def duration(delta: float) -> float:
        if delta == 0.0:
            return 0.0
        return Turn(delta, math.radians(params.turn_rate), params.turn_acceleration,
                    params.control_period).duration

    steps = []
    for k in range(1, 1 + math.ceil(duration(MAX_ROTATION) / tau)):
        lo, hi = 0.0, MAX_ROTATION
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if duration(mid) <= k * tau else (lo, mid)
        steps.append(lo)
    return np.array(steps)


def _from_stored(dynamics: dict, spacing: float, headings: int, key: str, header: dict,
                 arrays: dict, path: Path) -> BumpTable | None:
    """The table from a cache file's arrays, or None (with a warning) when they do not fit."""
    pieces, intervals, offset, fields = _layout(dynamics, spacing, headings, key)
    n = int(offset[-1] + (intervals[-1] + 1) * headings)
    try:
        shapes = {"end": (n, 2), "heading": (n,), "normal": (n,), "end_piece": (n,),
                  "seconds": (n,)}
        for name, shape in shapes.items():
            if arrays[name].shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {arrays[name].shape}")
        if (arrays["end_piece"].min() < STAYS or arrays["end_piece"].max() >= pieces.n_pieces
                or np.isnan(arrays["seconds"]).any()):
            raise ValueError("node arrays out of range")
        took, lag = float(header["build_seconds"]), float(header["lag"])
        if not math.isfinite(lag):
            raise ValueError("its lag is not finite")
    except (ValueError, KeyError, TypeError) as exc:
        model_cache.warn_unusable(path, exc)
        return None
    return BumpTable(pieces=pieces, intervals=intervals, offset=offset, end=arrays["end"].astype(np.float64),
                     heading=arrays["heading"].astype(np.float64),
                     normal=arrays["normal"].astype(np.float64),
                     end_piece=arrays["end_piece"].astype(np.int64),
                     seconds=arrays["seconds"].astype(np.float64), build_seconds=took, lag=lag,
                     **fields)


class BumpMotion:
    """How planners move robots from bump to bump: through the table where it applies, else
    through the simulator (`bump_motion`).

    Attributes:
        model, dynamics: the cell model of the decision states and the `BounceDynamics`
            arguments (with the ``world``).
        table: the `BumpTable`, or None where the simulator is used. Given as a table or as
            ``load``, a function that returns it (`bump_table` with its arguments bound): then
            it is loaded or built at its first use, not when the motion is made — an env that
            is only constructed (a configuration's validation reads its horizon) builds none.
    """

    def __init__(self, model: CellModel, dynamics: dict, table: BumpTable | None = None, *,
                 load: Callable[[], BumpTable] | None = None) -> None:
        self.model, self.dynamics = model, dict(dynamics)
        self._table, self._load = table, load

    @property
    def table(self) -> BumpTable | None:
        if self._table is None and self._load is not None:
            self._table, self._load = self._load(), None
        return self._table

    def bumps(self, angles: np.ndarray, action: np.ndarray, point: np.ndarray,
              heading: np.ndarray, rng: np.random.Generator, max_ticks: int) -> BumpOutcomes:
        """Robots at bump poses bump with ``angles[action]`` and drive to their next bump: one
        outcome per robot, as `bump_sampler.simulate_bumps`."""
        if self.table is None:
            return simulate_bumps(self.model, angles, action, point, heading, rng,
                                  self.dynamics, max_ticks)
        return self.table.bumps(self.model, angles, action, point, heading, rng,
                                self.dynamics.get("noise"), max_ticks)

    def reset_drives(self, point: np.ndarray, heading: np.ndarray, rng: np.random.Generator,
                     max_ticks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Robots at rest at interior poses drive to their first contact: decision states,
        contact points, headings, clocks, as `bump_sampler.reset_drives` (the table draws
        nothing from ``rng``)."""
        if self.table is None:
            return reset_drives(self.model, self.dynamics, point, heading, rng, max_ticks)
        return self.table.reset_drives(self.model, point, heading, max_ticks)


def bump_motion(model: CellModel, dynamics: dict, tabulated: bool | None = None, *,
                spacing: float = DEFAULT_SPACING, headings: int = DEFAULT_HEADINGS,
                cache: Path | str | bool | None = None) -> BumpMotion:
    """The bump-to-bump motion of ``dynamics`` for planners (module docstring): the table
    (`bump_table`, with ``spacing``, ``headings`` and ``cache``) where it applies and
    ``tabulated`` is not False — True insists on it —, the simulator otherwise."""
    if tabulated is False or (tabulated is None and not table_applies(dynamics)):
        return BumpMotion(model, dynamics)
    _check_table_arguments(dynamics, spacing, headings)
    return BumpMotion(model, dynamics,
                      load=functools.partial(bump_table, dynamics, spacing, headings, cache))
