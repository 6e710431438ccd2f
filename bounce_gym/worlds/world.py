"""The immutable `World`: a polygon with holes, validated on construction.

Conventions (see ARCHITECTURE.md): the outer ring is stored counter-clockwise and every hole
clockwise, so each directed edge ``(v_k, v_{k+1})`` has free space on its **left** and its inward
normal is the tangent rotated by +90 degrees (Nilles et al., IJRR 2021, section 2 frames).
Edges of all rings are flattened into one array; edge ``k`` starts at vertex ``k``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import cached_property, lru_cache

import numpy as np
import shapely
from shapely.geometry import Polygon

from bounce_gym.errors import ConfigError, InvalidWorldError
from bounce_gym.worlds import raycast
from bounce_gym.worlds.rings import (
    as_ring,
    check_holes,
    check_ring_shape,
    checked_holes,
    edges,
    signed_area,
)

#: Relative tolerance (times the world's diameter) for geometric predicates.
REL_TOL = 1e-9
#: The shortest length an argument may give in a world (a step, a robot radius, a cell side, a
#: goal radius), as a fraction of the world's diameter (`World.check_length`): a drive across the
#: world then takes at most 10^4 ticks.
MIN_LENGTH_FRACTION = 1e-4
#: The most cells of a grid over a world's bounding box that an argument may ask for
#: (`World.check_grid`): 2^20, a 1024 x 1024 grid.
MAX_GRID_CELLS = 1 << 20


class World:
    """A bounded polygonal workspace with polygonal holes (obstacles).

    Args:
        outer: vertices of the outer boundary, any orientation (stored counter-clockwise).
        holes: vertices of each obstacle, any orientation (stored clockwise).
        name: a label used in reprs, renders and result tables.

    Raises:
        InvalidWorldError: non-finite coordinates, fewer than 3 vertices, zero-length edges,
            repeated or collinear-degenerate vertices, self-intersecting rings, a hole that is
            not strictly inside the outer ring, or holes that overlap or touch.

    The world is immutable: arrays are read-only and attributes cannot be rebound. It pickles
    by value and compares equal to any world with the same rings.
    """

    __slots__ = (
        "name",
        "outer",
        "holes",
        "edge_start",
        "edge_end",
        "edge_ring",
        "tangents",
        "normals",
        "lengths",
        "reflex",
        "tol",
        "__dict__",  # cached_property storage (derived, never part of identity)
    )
    # the slots' types (set once in __init__ through object.__setattr__)
    name: str
    outer: np.ndarray
    holes: tuple[np.ndarray, ...]
    edge_start: np.ndarray
    edge_end: np.ndarray
    edge_ring: np.ndarray
    tangents: np.ndarray
    normals: np.ndarray
    lengths: np.ndarray
    reflex: np.ndarray
    tol: float

    def __init__(
        self,
        outer: Sequence[Sequence[float]] | np.ndarray,
        holes: Sequence[Sequence[Sequence[float]] | np.ndarray] = (),
        name: str | None = None,
    ) -> None:
        outer_ring = as_ring(outer, "outer ring")
        span = np.ptp(outer_ring, axis=0)
        tol = REL_TOL * max(float(np.hypot(*span)), 1e-300)
        check_ring_shape(outer_ring, "outer ring", tol)
        if signed_area(outer_ring) < 0:
            outer_ring = outer_ring[::-1].copy()
        if isinstance(holes, np.ndarray) and holes.ndim == 2:
            raise InvalidWorldError("holes: expected a list of rings, got a single (n, 2) array")
        hole_rings = checked_holes(holes, tol)
        check_holes(outer_ring, hole_rings)

        edge_start, edge_end, edge_ring, reflex = edges([outer_ring, *hole_rings])
        vec = edge_end - edge_start
        lengths = np.hypot(vec[:, 0], vec[:, 1])
        tangents = vec / lengths[:, None]
        normals = np.column_stack((-tangents[:, 1], tangents[:, 0]))

        set_ = object.__setattr__
        set_(self, "name", str(name) if name is not None else "world")
        set_(self, "outer", _frozen(outer_ring))
        set_(self, "holes", tuple(_frozen(h) for h in hole_rings))
        set_(self, "edge_start", _frozen(edge_start))
        set_(self, "edge_end", _frozen(edge_end))
        set_(self, "edge_ring", _frozen(edge_ring))
        set_(self, "tangents", _frozen(tangents))
        set_(self, "normals", _frozen(normals))
        set_(self, "lengths", _frozen(lengths))
        set_(self, "reflex", _frozen(reflex))
        set_(self, "tol", tol)

    # -- identity ---------------------------------------------------------------------------
    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"World is immutable; cannot set {key!r}")

    def __delattr__(self, key: str) -> None:
        raise AttributeError(f"World is immutable; cannot delete {key!r}")

    def __reduce__(self):
        return (World, (self.outer.copy(), [h.copy() for h in self.holes], self.name))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, World):
            return NotImplemented
        return (
            len(self.holes) == len(other.holes)
            and np.array_equal(self.outer, other.outer)
            and all(np.array_equal(a, b) for a, b in zip(self.holes, other.holes, strict=True))
        )

    def __hash__(self) -> int:
        return hash((self.outer.tobytes(), tuple(h.tobytes() for h in self.holes)))

    def __repr__(self) -> str:
        return (
            f"World(name={self.name!r}, vertices={len(self.outer)}, holes={len(self.holes)}, "
            f"bounds={tuple(round(b, 6) for b in self.bounds)})"
        )

    # -- derived geometry -------------------------------------------------------------------
    @property
    def rings(self) -> tuple[np.ndarray, ...]:
        """Outer ring first, then the holes."""
        return (self.outer, *self.holes)

    @property
    def n_edges(self) -> int:
        return len(self.lengths)

    @cached_property
    def polygon(self) -> Polygon:
        """The free space as a shapely polygon."""
        return Polygon(self.outer, list(self.holes))

    @cached_property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the outer ring."""
        lo, hi = self.outer.min(axis=0), self.outer.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    @property
    def area(self) -> float:
        return float(self.polygon.area)

    @cached_property
    def diameter(self) -> float:
        """Length of the bounding-box diagonal; the scale for tolerances."""
        xmin, ymin, xmax, ymax = self.bounds
        return float(np.hypot(xmax - xmin, ymax - ymin))

    def check_length(self, field: str, value: float, *, top: float = 1.0,
                     zero: bool = False, open_top: bool = False) -> float:
        """Raise `ConfigError` naming ``field`` unless the length ``value`` (world units) lies
        in [`MIN_LENGTH_FRACTION`, ``top``] times the world's `diameter` (``open_top``: below
        the top; ``zero``: 0 is allowed too); returns it. The bounds of the length arguments
        of the envs and tasks (docs: Environments, "Lengths and scales")."""
        low, high = MIN_LENGTH_FRACTION * self.diameter, top * self.diameter
        if (zero and value == 0) or (low <= value and (value < high if open_top
                                                       else value <= high)):
            return value
        top_text = "the" if top == 1 else f"{top:g} times the"
        raise ConfigError(
            f"{field}: expected {'0 or ' if zero else ''}a length in [{low:.3g}, {high:.3g}"
            f"{')' if open_top else ']'} ({MIN_LENGTH_FRACTION:g} to {top_text} diameter "
            f"{self.diameter:.4g} of world {self.name!r}), got {value!r}")

    def grid_shape(self, cell_size: float) -> tuple[int, int]:
        """(rows, cols) of the grid of cells of side ``cell_size`` over the bounding box (as
        `occupancy` lays it out)."""
        xmin, ymin, xmax, ymax = self.bounds
        return (math.ceil((ymax - ymin) / cell_size - 1e-9),
                math.ceil((xmax - xmin) / cell_size - 1e-9))

    def check_grid(self, field: str, cell_size: float, limit: int = MAX_GRID_CELLS,
                   per_cell: int = 1, what: str = "cells") -> tuple[int, int]:
        """Raise `ConfigError` naming ``field`` if the grid of cells of side ``cell_size``
        over the bounding box has more than ``limit`` cells (times ``per_cell``, e.g. the
        orientation bins of a cell model's states: ``what`` names them); else its (rows,
        cols)."""
        rows, cols = self.grid_shape(cell_size)
        count = rows * cols * per_cell
        if count > limit:
            xmin, ymin, xmax, ymax = self.bounds
            smallest = self._smallest_cell(limit / per_cell)
            raise ConfigError(
                f"{field}: cells of side {cell_size:g} cut world {self.name!r} "
                f"({xmax - xmin:g} x {ymax - ymin:g}) into {rows:,} x {cols:,} cells"
                f"{f' x {per_cell:,} bins' if per_cell > 1 else ''} = {count:,} {what}; at most "
                f"{limit:,} (cells of side >= {smallest:.3g})")
        return rows, cols

    def _smallest_cell(self, cells: float) -> float:
        """A cell side, rounded up to three digits, whose grid has at most ``cells`` cells."""
        xmin, ymin, xmax, ymax = self.bounds
        side = math.sqrt((xmax - xmin) * (ymax - ymin) / cells)
        step = 10.0 ** (math.floor(math.log10(side)) - 2)
        side = math.ceil(side / step) * step
        while math.prod(self.grid_shape(side)) > cells:
            side += step
        return side

    @property
    def perimeter(self) -> float:
        return float(self.lengths.sum())

    # -- queries ----------------------------------------------------------------------------
    def first_hit(
        self, origins: np.ndarray, directions: np.ndarray, radius: float = 0.0
    ) -> raycast.Hits:
        """First boundary contact of many rays (or swept disks) at once.

        Args:
            origins: (n, 2) ray origins, inside the free space (for ``radius > 0``: at least
                ``radius`` away from the boundary).
            directions: (n, 2) unit directions.
            radius: radius of the swept disk; 0 for a point.

        Returns:
            `raycast.Hits` with ``distance`` (n,), ``edge`` (n,), ``vertex`` (n,) and inward
            unit ``normal`` (n, 2) at the contact. See `bounce_gym.worlds.raycast.first_hit`.
        """
        return raycast.first_hit(self, origins, directions, radius)

    def contains(self, points: np.ndarray, radius: float = 0.0) -> np.ndarray:
        """Whether each point (n, 2) lies in the free space at least ``radius`` from the boundary.

        Points on the boundary (within the world's tolerance) count as inside.
        """
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        dist = self.boundary_distance(pts)
        inside = shapely.contains_xy(self.polygon, pts[:, 0], pts[:, 1])
        return (inside | (dist <= self.tol)) & (dist >= radius - self.tol)

    def boundary_distance(self, points: np.ndarray) -> np.ndarray:
        """Euclidean distance from each point (n, 2) to the nearest boundary edge."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        vec = self.edge_end - self.edge_start
        chunk = max(1, _PAIRS_PER_CHUNK // self.n_edges)  # bounded memory for many points
        out = np.empty(len(pts))
        for k in range(0, len(pts), chunk):
            rel = pts[k : k + chunk, None, :] - self.edge_start[None, :, :]
            s = np.clip(np.einsum("nek,ek->ne", rel, vec) / (self.lengths**2), 0.0, 1.0)
            closest = rel - s[..., None] * vec[None]
            out[k : k + chunk] = np.sqrt(np.min(np.einsum("nek,nek->ne", closest, closest), axis=1))
        return out

    def eroded(self, radius: float, quad_segs: int = 16):
        """Configuration space of a disk robot of ``radius``: the free space shrunk by it.

        Returns a shapely geometry (Polygon, MultiPolygon if a passage closes, or empty). Arcs
        around reflex vertices are approximated with ``quad_segs`` segments per quarter circle;
        the kinematic backend does not use this approximation (it sweeps the disk exactly).
        """
        if not np.isfinite(radius) or radius < 0:
            raise InvalidWorldError(f"radius must be a finite number >= 0, got {radius!r}")
        return self._eroded(float(radius), int(quad_segs))

    @lru_cache(maxsize=8)  # noqa: B019 (worlds are immutable and hashable)
    def _eroded(self, radius: float, quad_segs: int):
        if radius == 0:
            return self.polygon
        return self.polygon.buffer(-radius, quad_segs=quad_segs)

    def occupancy(self, cell_size: float = 1.0, radius: float = 0.0) -> np.ndarray:
        """Free/blocked grid over the bounding box for the cell model.

        Cell ``(row, col)`` spans ``[xmin + col*s, xmin + (col+1)*s) x [ymin + row*s, ...)``;
        row 0 is the **bottom** row (y points up). A cell is free iff its centre lies in the free
        space at least ``radius`` from the boundary (the papers' C-space for a disk robot).

        Returns:
            bool array of shape (rows, cols), True = free.
        """
        if not np.isfinite(cell_size) or cell_size <= 0:
            raise InvalidWorldError(f"cell_size must be a finite number > 0, got {cell_size!r}")
        xmin, ymin = self.bounds[:2]
        rows, cols = self.grid_shape(cell_size)
        cx = xmin + (np.arange(cols) + 0.5) * cell_size
        cy = ymin + (np.arange(rows) + 0.5) * cell_size
        gx, gy = np.meshgrid(cx, cy)
        centres = np.column_stack((gx.ravel(), gy.ravel()))
        inside = shapely.contains_xy(self.polygon, centres[:, 0], centres[:, 1])
        if radius > 0:
            inside[inside] = self._clear_of_boundary(centres[inside], radius)
        return inside.reshape(rows, cols)

    def _clear_of_boundary(self, points: np.ndarray, radius: float) -> np.ndarray:
        """``boundary_distance(points) >= radius`` without all the point–edge pairs.

        With many edges (a grid map with many obstacles), an R-tree of the edges
        (`shapely.STRtree`) gives for every point the edges whose bounding box comes within
        ``radius`` (plus a margin) of it, and the distances to those alone are computed, with
        `boundary_distance`'s arithmetic: an edge outside that reach is farther than ``radius``,
        so the result is the same, in time and memory that grow with the points and the nearby
        pairs instead of points × edges.
        """
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if self.n_edges <= _INDEXED_EDGES:
            return self.boundary_distance(pts) >= radius
        reach = radius * (1 + 1e-6) + self.tol
        vec = self.edge_end - self.edge_start
        out = np.ones(len(pts), dtype=bool)
        for k in range(0, len(pts), _POINTS_PER_QUERY):
            chunk = pts[k : k + _POINTS_PER_QUERY]
            lo, hi = chunk - reach, chunk + reach
            boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
            point, edge = self._edge_tree.query(boxes)
            rel = chunk[point] - self.edge_start[edge]
            s = np.clip(np.einsum("pk,pk->p", rel, vec[edge]) / (self.lengths[edge] ** 2),
                        0.0, 1.0)
            closest = rel - s[:, None] * vec[edge]
            near = np.sqrt(np.einsum("pk,pk->p", closest, closest)) < radius
            out[k + point[near]] = False
        return out

    @cached_property
    def _edge_tree(self) -> shapely.STRtree:
        """An R-tree of the boundary edges (as line segments, in edge order)."""
        return shapely.STRtree(shapely.linestrings(np.stack((self.edge_start, self.edge_end),
                                                            axis=1)))

    def sample_free(self, rng: np.random.Generator, n: int, radius: float = 0.0) -> np.ndarray:
        """Draw ``n`` points uniformly from the free space more than ``radius`` from the boundary.

        Rejection sampling in the bounding box when the C-space (`eroded`) fills at least
        1/64 of it; otherwise (a thin or small C-space) uniform points of a triangulation of the
        C-space, kept if they pass the same exact test. Both stop after a bounded number of
        rounds.

        Raises:
            InvalidWorldError: the C-space is empty (at once), or too few points passed in the
                allowed rounds.
        """
        region = self.eroded(radius)
        if region.area <= self.tol**2:
            raise InvalidWorldError(
                f"world {self.name!r}: no free space for a robot of radius {radius}: the free "
                "space shrunk by the radius is empty"
            )
        xmin, ymin, xmax, ymax = self.bounds
        in_box = region.area * 64 >= (xmax - xmin) * (ymax - ymin)
        out = np.empty((0, 2))
        for _ in range(1000 if in_box else 100):
            need = n - len(out)
            if need <= 0:
                break
            batch = max(64, 4 * need)
            if in_box:
                pts = rng.uniform((xmin, ymin), (xmax, ymax), size=(batch, 2))
            else:
                pts = sample_in(region, rng, batch)
            ok = shapely.contains_xy(self.polygon, pts[:, 0], pts[:, 1])
            ok &= self.boundary_distance(pts) > radius + self.tol
            out = np.concatenate((out, pts[ok][:need]))
        if len(out) < n:
            raise InvalidWorldError(
                f"world {self.name!r}: no free space for a robot of radius {radius}"
            )
        return out

    # -- serialisation ----------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The polygon form of the map schema (see `bounce_gym.worlds.io`)."""
        return {
            "name": self.name,
            "outer": self.outer.tolist(),
            "holes": [h.tolist() for h in self.holes],
        }


def sample_in(region, rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` uniform points of a shapely (Multi)Polygon of positive area: a triangle of its
    constrained Delaunay triangulation chosen by area, then a uniform point of the triangle."""
    triangles = shapely.get_parts(shapely.constrained_delaunay_triangles(region))
    corners = shapely.get_coordinates(shapely.get_exterior_ring(triangles)).reshape(-1, 4, 2)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    ab, ac = b - a, c - a
    area = 0.5 * np.abs(ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0])
    pick = rng.choice(len(area), size=n, p=area / area.sum())
    u, v = rng.uniform(size=(2, n, 1))
    flip = u + v > 1
    u, v = np.where(flip, 1 - u, u), np.where(flip, 1 - v, v)
    return a[pick] + u * ab[pick] + v * ac[pick]


#: Point-edge pairs `World.boundary_distance` handles at once.
_PAIRS_PER_CHUNK = 1 << 20
#: Above this many edges, `World.occupancy` finds the edges near a cell centre with an R-tree.
_INDEXED_EDGES = 64
#: Points `World.occupancy` queries the R-tree with at once.
_POINTS_PER_QUERY = 1 << 14


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array)
    array.setflags(write=False)
    return array
