"""Visibility-based boundary partition P' of a polygon (Nilles et al., IJRR 2021, Alg. 1).

Nilles et al. 2021, §4. For every reflex vertex ``r`` and every vertex ``v`` that ``r`` sees, the
ray from ``v`` through ``r`` is continued beyond ``r`` when the line grazes ``r`` (rule (a)); the
two neighbours of ``r`` are always used, so the extensions of ``r``'s incident edges are shot
(rule (b)). First hits are inserted into ∂P unless they coincide with an existing vertex, and
coincident hits are merged, both with scale-relative tolerances (rule (c); docs/choices/visibility.md,
"Tolerances relative to the polygon's size"). Reflexness is
taken with respect to free space, which with the World's ring orientation (outer CCW, holes CW)
is the same cross-product test on every ring (rule (d)). Inserted vertices shoot nothing.

Numbering: segments of ∂P' follow the world's flat edge order — outer ring first, starting at the
world's first vertex, counter-clockwise; then each hole (clockwise) — and inside an original edge
the inserted vertices are sorted from the edge's start. Segment ``k`` starts at vertex ``k``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import shapely
from shapely.geometry import Polygon

from bounce_gym.worlds.world import World

__all__ = ["Partition", "closed_region", "partition", "visible_pairs"]

#: Merge / vertex-coincidence tolerance for inserted points, times the world's diameter
#: (docs/choices/visibility.md, "Tolerances relative to the polygon's size").
SNAP_REL = 1e-9
#: Slack of the closed-visibility predicates, times the world's diameter.
VIS_REL = 1e-9
#: Relative tolerance of the sidedness (grazing) test on unit-normalised cross products.
SIDE_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class Partition:
    """The segments of ∂P' (arrays of length m, one row per segment).

    Attributes:
        world: the partitioned `World`.
        start, end: (m, 2) segment end points; ``start[k]`` is vertex ``k`` of P'.
        ring: (m,) ring of the segment (0 = outer boundary, 1.. = holes).
        edge: (m,) index of the original world edge containing the segment.
        tangent, normal: (m, 2) unit tangent and inward (free-space) normal.
        length: (m,) segment lengths.
        reflex: (m,) vertex ``k`` is a reflex vertex of P.
        inserted: (m,) vertex ``k`` was inserted by Algorithm 1 (interior angle π).
        succ, pred: (m,) index of the next / previous segment on the same ring.
        closed: the visibility semantics used (True: closed, grazing counts; docs/choices/visibility.md,
            "Closed visibility").
        tol: absolute length tolerance used for snapping and the predicates.
    """

    world: World
    start: np.ndarray
    end: np.ndarray
    ring: np.ndarray
    edge: np.ndarray
    tangent: np.ndarray
    normal: np.ndarray
    length: np.ndarray
    reflex: np.ndarray
    inserted: np.ndarray
    succ: np.ndarray
    pred: np.ndarray
    closed: bool
    tol: float

    @property
    def n(self) -> int:
        return len(self.length)

    def __len__(self) -> int:
        return self.n

    @property
    def vertices(self) -> np.ndarray:
        """(m, 2) vertices of P' (vertex ``k`` = start of segment ``k``)."""
        return self.start

    @property
    def perimeter(self) -> float:
        return float(self.length.sum())

    def segment(self, k: int) -> np.ndarray:
        """(2, 2) array ``[start, end]`` of segment ``k``."""
        return np.stack((self.start[k], self.end[k]))

    @cached_property
    def _edge_offsets(self) -> tuple[np.ndarray, list[np.ndarray]]:
        first = np.searchsorted(self.edge, np.arange(self.world.n_edges))
        cuts = []
        for e in range(self.world.n_edges):
            ks = np.flatnonzero(self.edge == e)
            cuts.append(np.dot(self.start[ks] - self.world.edge_start[e],
                               self.world.tangents[e]))
        return first, cuts

    def locate(self, edges: np.ndarray, points: np.ndarray) -> np.ndarray:
        """P' segment containing each point (n, 2) that lies on the given world edge (n,)."""
        edges = np.asarray(edges, dtype=np.int64).reshape(-1)
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        first, cuts = self._edge_offsets
        out = np.full(len(edges), -1, dtype=np.int64)
        for i, (e, p) in enumerate(zip(edges, points, strict=True)):
            if e < 0:
                continue
            s = float(np.dot(p - self.world.edge_start[e], self.world.tangents[e]))
            out[i] = first[e] + max(int(np.searchsorted(cuts[e], s, side="right")) - 1, 0)
        return out


def closed_region(world: World, eps: float | None = None) -> Polygon:
    """The free space grown by ``eps`` (default ``VIS_REL * diameter``), prepared.

    A segment lies in the *closed* free space up to the tolerance iff this region covers it.
    Mitred joins keep the growth uniform at the convex corners of the region.
    """
    eps = VIS_REL * world.diameter if eps is None else eps
    cache = world.__dict__.setdefault("_visibility_regions", {})
    region = cache.get(eps)
    if region is None:
        region = world.polygon.buffer(eps, join_style="mitre", mitre_limit=10.0)
        shapely.prepare(region)
        cache[eps] = region
    return region


def visible_pairs(world: World, a: np.ndarray, b: np.ndarray, closed: bool = True,
                  exclude_points: np.ndarray | None = None) -> np.ndarray:
    """Whether each segment ``a[k]``–``b[k]`` is a line of sight in P.

    closed=True: the closed segment lies in the closed free space (grazing a vertex or running
    along the boundary counts). closed=False: additionally no vertex of ``exclude_points``
    (default: the world's vertices) other than the segment's own end points lies on it, i.e.
    the open segment avoids ∂P (docs/choices/visibility.md, "Closed visibility"; valid for segments with end
    points on ∂P).
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 2)
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    eps = VIS_REL * world.diameter
    lines = shapely.linestrings(np.stack((a, b), axis=1))
    ok = shapely.covers(closed_region(world, eps), lines)
    if closed:
        return ok
    pts = world.edge_start if exclude_points is None else exclude_points
    return ok & ~_touches_points(lines, [a, b], pts, eps)


def _touches_points(geoms, ends: list[np.ndarray], pts: np.ndarray, eps: float,
                    tree: shapely.STRtree | None = None) -> np.ndarray:
    """Whether a point of ``pts`` other than the geometry's own corners ``ends`` is within eps
    (``tree``: an STRtree of ``pts`` as points, if one is at hand)."""
    tree = shapely.STRtree(shapely.points(pts)) if tree is None else tree
    gi, pi = tree.query(geoms, predicate="dwithin", distance=eps)
    other = np.ones(len(gi), dtype=bool)
    for e in ends:
        gap = pts[pi] - e[gi]
        other &= np.hypot(gap[:, 0], gap[:, 1]) > eps
    return np.bincount(gi[other], minlength=len(geoms)) > 0


def _grazes(v: np.ndarray, r: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rule (a): both neighbours a, b of r lie on the same closed side of the line v–r."""
    u = r - v
    u /= np.hypot(u[:, 0], u[:, 1])[:, None]

    def side(w):
        rel = w - r
        return (u[:, 0] * rel[:, 1] - u[:, 1] * rel[:, 0]) / np.hypot(rel[:, 0], rel[:, 1])

    sa, sb = side(a), side(b)
    return ((sa >= -SIDE_TOL) & (sb >= -SIDE_TOL)) | ((sa <= SIDE_TOL) & (sb <= SIDE_TOL))


def _ring_neighbours(world: World) -> tuple[np.ndarray, np.ndarray]:
    """Flat index of the previous and next vertex on the same ring."""
    n = world.n_edges
    prev, nxt = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    offset = 0
    for ring in world.rings:
        idx = offset + np.arange(len(ring))
        prev[idx] = np.roll(idx, 1)
        nxt[idx] = np.roll(idx, -1)
        offset += len(ring)
    return prev, nxt


def event_points(world: World, closed: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The raw first hits of Algorithm 1: (edge ids (k,), points (k, 2)), not deduplicated."""
    verts = world.edge_start
    n = len(verts)
    prev, nxt = _ring_neighbours(world)
    reflex = np.flatnonzero(world.reflex)
    if len(reflex) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    rr = np.repeat(reflex, n)
    vv = np.tile(np.arange(n), len(reflex))
    keep = vv != rr
    rr, vv = rr[keep], vv[keep]
    neighbour = (vv == prev[rr]) | (vv == nxt[rr])
    graze = _grazes(verts[vv], verts[rr], verts[prev[rr]], verts[nxt[rr]])
    cand = graze | neighbour
    rr, vv, neighbour = rr[cand], vv[cand], neighbour[cand]
    seen = neighbour.copy()
    other = ~neighbour
    seen[other] = visible_pairs(world, verts[rr[other]], verts[vv[other]], closed)
    rr, vv = rr[seen], vv[seen]
    origin = verts[rr]
    direction = origin - verts[vv]
    direction /= np.hypot(direction[:, 0], direction[:, 1])[:, None]
    # a ray running along an incident edge of r (v, r and a neighbour collinear, the neighbour
    # beyond r) has the neighbour, an existing vertex, as its event point: nothing to insert
    along = np.zeros(len(rr), dtype=bool)
    for nb in (prev[rr], nxt[rr]):
        rel = verts[nb] - origin
        dist = np.hypot(rel[:, 0], rel[:, 1])
        cross = (direction[:, 0] * rel[:, 1] - direction[:, 1] * rel[:, 0]) / dist
        along |= (np.abs(cross) <= SIDE_TOL) & (np.einsum("ij,ij->i", rel, direction) > 0)
    origin, direction = origin[~along], direction[~along]
    if len(origin) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    # start a hair beyond r: from r itself the incident edge ending at r registers a contact
    # at distance 0 (the ray crosses that edge's supporting line at its end point)
    origin = origin + (100.0 * world.tol) * direction
    hits = world.first_hit(origin, direction)
    ok = (hits.edge >= 0) & np.isfinite(hits.distance)
    points = origin[ok] + hits.distance[ok, None] * direction[ok]
    return hits.edge[ok], points


def partition(world: World, closed: bool = True) -> Partition:
    """Algorithm 1 (PartitionPoly): the boundary partition P' of ``world`` (Nilles et al.
    2021, §4).

    Args:
        world: the polygon (holes allowed).
        closed: visibility semantics for "v is visible from r" (True: grazing counts;
            docs/choices/visibility.md, "Closed visibility").
    """
    snap = SNAP_REL * world.diameter
    edges, points = event_points(world, closed)
    params: list[list[float]] = [[] for _ in range(world.n_edges)]
    for e, p in zip(edges, points, strict=True):
        s = float(np.dot(p - world.edge_start[e], world.tangents[e]))
        if s <= snap or s >= world.lengths[e] - snap:
            continue  # rule (c): coincides with an existing vertex
        params[e].append(s)

    start, ring, edge, inserted, reflex = [], [], [], [], []
    for e in range(world.n_edges):
        cuts = [0.0]
        for s in sorted(params[e]):
            if s - cuts[-1] > snap:  # rule (c): merge coincident hits
                cuts.append(s)
        pts = world.edge_start[e] + np.asarray(cuts)[:, None] * world.tangents[e]
        start.extend(pts)
        ring.extend([int(world.edge_ring[e])] * len(cuts))
        edge.extend([e] * len(cuts))
        inserted.extend([False] + [True] * (len(cuts) - 1))
        reflex.extend([bool(world.reflex[e])] + [False] * (len(cuts) - 1))
    return assemble_partition(world, start, ring, edge, inserted, reflex, bool(closed),
                    VIS_REL * world.diameter)


def assemble_partition(world: World, start, ring, edge, inserted, reflex, closed: bool,
             tol: float) -> Partition:
    """A `Partition` from its segments' start points (ring by ring, in boundary order) and
    per-segment flags; ends, successors, tangents and inward normals are derived."""
    start = np.asarray(start, dtype=np.float64)
    ring = np.asarray(ring, dtype=np.int64)
    m = len(start)
    succ = np.arange(1, m + 1)
    for r in np.unique(ring):
        idx = np.flatnonzero(ring == r)
        succ[idx[-1]] = idx[0]
    pred = np.empty(m, dtype=np.int64)
    pred[succ] = np.arange(m)
    end = start[succ]
    vec = end - start
    length = np.hypot(vec[:, 0], vec[:, 1])
    tangent = vec / length[:, None]
    normal = np.column_stack((-tangent[:, 1], tangent[:, 0]))
    return Partition(
        world=world, start=start, end=end, ring=ring, edge=np.asarray(edge, dtype=np.int64),
        tangent=tangent, normal=normal, length=length, reflex=np.asarray(reflex),
        inserted=np.asarray(inserted), succ=succ, pred=pred, closed=closed, tol=tol,
    )
