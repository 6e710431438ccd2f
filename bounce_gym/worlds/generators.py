"""Seeded random worlds: star polygons, trees of rooms, and grid maps with rectangular obstacles.

Every generator takes a `numpy.random.Generator` as its first argument and draws all randomness
from it (never from the global RNG), so the same seed gives an equal world. Bad arguments raise
`bounce_gym.errors.ConfigError` naming the argument and the allowed values.
"""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral, Real

import numpy as np
import shapely
from shapely.geometry import Polygon, box

from bounce_gym.errors import ConfigError, InvalidWorldError
from bounce_gym.worlds.grid import world_from_grid
from bounce_gym.worlds.world import World

__all__ = ["random_grid", "random_room_tree", "random_star_polygon"]


def random_star_polygon(
    rng: np.random.Generator,
    n_vertices: int = 20,
    center: Sequence[float] = (250.0, 250.0),
    avg_radius: float = 100.0,
    irregularity: float = 0.2,
    spikiness: float = 0.3,
    *,
    max_attempts: int = 1000,
    name: str = "star",
) -> World:
    """A random star-shaped polygon (Ounsworth's generator, as used by Nilles et al. 2021).

    The vertices sit at increasing angles around ``center``: the angle starts at
    ``U[0, 2*pi)``, and the ``n`` angular steps are drawn from
    ``U[2*pi/n - irregularity, 2*pi/n + irregularity]`` and then rescaled to sum to ``2*pi``.
    Radii are ``N(avg_radius, spikiness * avg_radius)`` clipped to ``[0, 2 * avg_radius]``.
    ``irregularity`` is in **raw radians**, as in the authors' experiments (IJRR 2021 Figs. 15-16
    use irregularity in linspace(0.1, 0.4, 5) and spikiness in linspace(0.1, 0.5, 5), n = 20,
    centre (250, 250), average radius 100). With ``irregularity > 2*pi/n`` a step may be negative,
    and the polygon may self-intersect; such draws (and any other invalid polygon) are rejected
    and redrawn, up to ``max_attempts`` times.

    Raises:
        ConfigError: a bad argument, or no valid polygon in ``max_attempts`` draws.
    """
    _check_rng(rng)
    n = _int_arg("n_vertices", n_vertices, minimum=3)
    cx, cy = _point_arg("center", center)
    avg = _real_arg("avg_radius", avg_radius, positive=True)
    irr = _real_arg("irregularity", irregularity)
    spike = _real_arg("spikiness", spikiness)
    attempts = _int_arg("max_attempts", max_attempts, minimum=1)
    mean_step = 2.0 * np.pi / n
    for _ in range(attempts):
        steps = rng.uniform(mean_step - irr, mean_step + irr, size=n)
        steps *= 2.0 * np.pi / steps.sum()
        start = rng.uniform(0.0, 2.0 * np.pi)
        radii = np.clip(rng.normal(avg, spike * avg, size=n), 0.0, 2.0 * avg)
        angles = start + np.concatenate(([0.0], np.cumsum(steps[:-1])))
        vertices = np.column_stack((cx + radii * np.cos(angles), cy + radii * np.sin(angles)))
        try:
            return World(vertices, name=name)
        except InvalidWorldError:
            continue
    raise ConfigError(
        f"random_star_polygon: no simple polygon in max_attempts={attempts} draws with "
        f"n_vertices={n}, irregularity={irr}, spikiness={spike}; lower irregularity (below "
        f"2*pi/n_vertices = {mean_step:.4g} steps are never negative) or raise max_attempts"
    )


def random_room_tree(
    rng: np.random.Generator,
    n_rooms: int = 4,
    room_size: tuple[float, float] = (4.0, 10.0),
    door_width: float = 1.0,
    wall: float = 0.5,
    *,
    max_attempts: int = 1000,
    name: str = "room_tree",
) -> World:
    """A tree of axis-aligned rectangular rooms joined by doors, as one simple polygon.

    The first room has its lower-left corner at the origin. Each further room picks a parent
    uniformly among the rooms placed so far and one of the parent's four sides uniformly; it is
    placed across a wall of thickness ``wall`` from that side, shifted along it so that the two
    rooms face each other over at least ``2 * door_width``. The door is a ``door_width`` wide,
    ``wall`` deep passage through the wall, centred uniformly where the rooms face each other and
    at least ``door_width / 2`` from the end of the shared stretch. Room widths and heights are
    drawn uniformly from ``room_size``. A room that would come closer than ``wall`` to any other
    room is redrawn, so rooms touch only through their doors: the free space is the union of the
    rooms and doors, a single polygon without holes whose room adjacency is a tree.

    Args:
        rng: the random generator.
        n_rooms: number of rooms, >= 1.
        room_size: (min, max) side length of a room, ``0 < min <= max``; ``min >= 2*door_width``
            so that a door fits.
        door_width: width of a door, > 0.
        wall: wall thickness (the length of each door passage), > 0.
        max_attempts: draws allowed for each room before giving up.
        name: the world's name.

    Raises:
        ConfigError: a bad argument, or a room that could not be placed in ``max_attempts``.
    """
    _check_rng(rng)
    n = _int_arg("n_rooms", n_rooms, minimum=1)
    if not isinstance(room_size, Sequence) or isinstance(room_size, str) or len(room_size) != 2:
        raise ConfigError(f"room_size: expected a pair (min, max), got {room_size!r}")
    lo = _real_arg("room_size[0]", room_size[0], positive=True)
    hi = _real_arg("room_size[1]", room_size[1], positive=True)
    if hi < lo:
        raise ConfigError(f"room_size: min must be <= max, got {room_size!r}")
    door = _real_arg("door_width", door_width, positive=True)
    if lo < 2 * door:
        raise ConfigError(
            f"room_size: min ({lo}) must be >= 2 * door_width ({2 * door}) for doors to fit"
        )
    thick = _real_arg("wall", wall, positive=True)
    attempts = _int_arg("max_attempts", max_attempts, minimum=1)

    w0, h0 = rng.uniform(lo, hi, size=2)
    rooms = [box(0.0, 0.0, float(w0), float(h0))]
    doors = []
    for k in range(1, n):
        for _ in range(attempts):
            parent = rooms[int(rng.integers(len(rooms)))]
            side = int(rng.integers(4))  # 0 east, 1 north, 2 west, 3 south
            w, h = (float(v) for v in rng.uniform(lo, hi, size=2))
            room, door_box = _attach(rng, parent, side, w, h, door, thick)
            if all(room.distance(other) >= thick * (1 - 1e-9) for other in rooms):
                rooms.append(room)
                doors.append(door_box)
                break
        else:
            raise ConfigError(
                f"random_room_tree: could not place room {k} in max_attempts={attempts} draws; "
                "lower n_rooms or raise max_attempts"
            )
    union = shapely.unary_union(rooms + doors)
    union = union.simplify(0)
    if not isinstance(union, Polygon) or union.interiors:  # pragma: no cover - by construction
        raise InvalidWorldError("random_room_tree: rooms did not merge into one simple polygon")
    return World(union.exterior.coords, name=name)


def _attach(rng, parent, side, w, h, door, thick):
    """Place a w x h room across the ``side`` wall of ``parent``; return (room, door box)."""
    px0, py0, px1, py1 = parent.bounds
    # Along the shared side the rooms must face each other over at least 2 * door.
    if side in (0, 2):  # east/west: the rooms share a vertical stretch
        y0 = rng.uniform(py0 - h + 2 * door, py1 - 2 * door)
        # The room's face across the wall is computed once and shared with the door box, so
        # that they touch exactly (no floating-point sliver between them).
        face = px1 + thick if side == 0 else px0 - thick
        room = box(face, y0, face + w, y0 + h) if side == 0 else box(face - w, y0, face, y0 + h)
        a, b = max(py0, y0), min(py1, y0 + h)
        c = rng.uniform(a + door, b - door)
        gx0, gx1 = (px1, face) if side == 0 else (face, px0)
        door_box = box(gx0, c - door / 2, gx1, c + door / 2)
    else:  # north/south: the rooms share a horizontal stretch
        x0 = rng.uniform(px0 - w + 2 * door, px1 - 2 * door)
        face = py1 + thick if side == 1 else py0 - thick
        room = box(x0, face, x0 + w, face + h) if side == 1 else box(x0, face - h, x0 + w, face)
        a, b = max(px0, x0), min(px1, x0 + w)
        c = rng.uniform(a + door, b - door)
        gy0, gy1 = (py1, face) if side == 1 else (face, py0)
        door_box = box(c - door / 2, gy0, c + door / 2, gy1)
    return room, door_box


def random_grid(
    rng: np.random.Generator,
    rows: int,
    cols: int,
    n_obstacles: int,
    max_size: int,
    *,
    cell_size: float = 1.0,
    max_attempts: int = 1000,
    name: str = "random_grid",
) -> World:
    """A ``rows x cols`` grid map with ``n_obstacles`` random rectangular obstacles.

    Each obstacle is a ``h x w`` block of cells with ``h, w`` uniform in ``1..max_size`` at a
    uniform position inside the grid (obstacles may overlap each other). A placement is redrawn
    when it would disconnect the free cells (4-connectivity), create a diagonal pinch (two free
    cells meeting only at a corner), or block a whole border row or column (so that
    ``world.occupancy(cell_size)`` has shape ``(rows, cols)`` and gives the grid back exactly).

    Raises:
        ConfigError: a bad argument, or an obstacle that could not be placed in ``max_attempts``
            draws (too many or too large obstacles for the grid).
    """
    _check_rng(rng)
    n_rows = _int_arg("rows", rows, minimum=1)
    n_cols = _int_arg("cols", cols, minimum=1)
    count = _int_arg("n_obstacles", n_obstacles, minimum=0)
    size = _int_arg("max_size", max_size, minimum=1)
    if size > min(n_rows, n_cols):
        raise ConfigError(
            f"max_size: must be <= min(rows, cols) = {min(n_rows, n_cols)}, got {size}"
        )
    cell = _real_arg("cell_size", cell_size, positive=True)
    attempts = _int_arg("max_attempts", max_attempts, minimum=1)
    free = np.ones((n_rows, n_cols), dtype=bool)
    for k in range(count):
        for _ in range(attempts):
            h, w = (int(v) for v in rng.integers(1, size + 1, size=2))
            r = int(rng.integers(0, n_rows - h + 1))
            c = int(rng.integers(0, n_cols - w + 1))
            candidate = free.copy()
            candidate[r : r + h, c : c + w] = False
            if _grid_ok(candidate):
                free = candidate
                break
        else:
            raise ConfigError(
                f"random_grid: could not place obstacle {k} of n_obstacles={count} in "
                f"max_attempts={attempts} draws on a {n_rows}x{n_cols} grid; use fewer or "
                "smaller obstacles"
            )
    return world_from_grid(free, cell, name=name)


def _grid_ok(free: np.ndarray) -> bool:
    """Connected (4-neighbours), no diagonal pinch, and a free cell in every border row/column."""
    if not (free[0].any() and free[-1].any() and free[:, 0].any() and free[:, -1].any()):
        return False
    a, b = free[:-1, :-1], free[1:, 1:]
    c, d = free[:-1, 1:], free[1:, :-1]
    if np.any((a & b & ~c & ~d) | (c & d & ~a & ~b)):
        return False
    from scipy import ndimage  # imported here: ~0.2 s that building an env does not need

    _, n_regions = ndimage.label(free)  # default structure: 4-connectivity
    return n_regions == 1


# -- argument checks --------------------------------------------------------------------------
def _check_rng(rng: object) -> None:
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(
            f"rng: expected a numpy.random.Generator (np.random.default_rng(seed)), "
            f"got {type(rng).__name__}"
        )


def _int_arg(label: str, value: object, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise ConfigError(f"{label}: must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _real_arg(label: str, value: object, positive: bool = False) -> float:
    bound = "> 0" if positive else ">= 0"
    if (
        isinstance(value, bool)
        or not isinstance(value, Real)
        or not np.isfinite(float(value))
        or value < 0
        or (positive and value == 0)
    ):
        raise ConfigError(f"{label}: must be a finite number {bound}, got {value!r}")
    return float(value)


def _point_arg(label: str, value: object) -> tuple[float, float]:
    try:
        point = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        point = np.empty(0)
    if point.shape != (2,) or not np.all(np.isfinite(point)):
        raise ConfigError(f"{label}: must be a pair of finite numbers (x, y), got {value!r}")
    return float(point[0]), float(point[1])
