"""Vectorised first-contact queries: rays (point robots) and swept disks against a `World`.

A disk of radius ``R`` moving along ``o + t d`` first touches the boundary either in the interior
of an edge — its centre then crosses the edge shifted by ``R`` along the inward normal — or at a
reflex vertex — its centre then crosses the circle of radius ``R`` about that vertex. Convex
vertices need no circle: the shifted edges meet before the disk can reach them. Taking the smallest
crossing time over both feature sets is exact (no polygonal approximation of the C-space arcs).

Only *approaching* crossings count (direction against the inward normal), so a robot resting on a
wall and heading into free space is not stopped by that wall, while one heading into it is stopped
at distance 0 — which is how the dynamics detects "still facing the wall" after a rotation.
Grazing is not a contact either: a ray parallel to an edge, or a disk that passes a reflex vertex
at exactly its radius (approach angle below `GRAZE` radians), slides on. Tangency is a measure-zero
event in random worlds but the rule in grid worlds, where a disk of half a cell moving along a row
of cell centres passes every obstacle corner at exactly its radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from bounce_gym.worlds.world import World

#: Upper bound on the size of the (rays x features) intermediate arrays, to cap memory.
_MAX_PAIRS = 1 << 21
#: Smallest approach angle (radians) at which a disk counts as hitting a vertex; sin²(GRAZE) · R²
#: bounds ``disc`` below. Passing closer than that overlaps the vertex by < R·GRAZE²/2 ≈ 5e-13 R.
GRAZE = 1e-6
#: Worlds with at most this many reflex vertices have them tested in a Python loop (`_cast_one`),
#: cheaper than numpy's per-call overhead on a few elements.
LOOP_VERTICES = 32


@dataclass(frozen=True)
class Hits:
    """Result of `first_hit` for n rays.

    Attributes:
        distance: (n,) travel distance to the contact, ``inf`` if the ray never hits (only
            possible for a ray that starts outside the free space).
        edge: (n,) index of the contacted edge; for a vertex contact, the edge starting there.
            -1 where there is no hit.
        vertex: (n,) index of the contacted reflex vertex (disk robots only), else -1.
        normal: (n, 2) unit normal at the contact, pointing into the free space; for a vertex
            contact it points from the vertex to the disk centre.
    """

    distance: np.ndarray
    edge: np.ndarray
    vertex: np.ndarray
    normal: np.ndarray


def first_hit(world: World, origins: np.ndarray, directions: np.ndarray, radius: float = 0.0) -> Hits:
    """First boundary contact along each ray; see the module docstring for the model."""
    o = np.asarray(origins, dtype=np.float64).reshape(-1, 2)
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 2)
    if o.shape != d.shape:
        raise ValueError(f"origins {o.shape} and directions {d.shape} must have the same shape")
    n = len(o)
    radius = float(radius)
    geometry = features(world, radius)
    if n == 1:
        return _first_hit_one(geometry, radius, o[0], d[0])
    step = max(1, _MAX_PAIRS // max(5 * geometry.n_edges + len(geometry.vx), 1))
    if n <= step:
        return _first_hit_chunk(geometry, radius, o, d)
    parts = [_first_hit_chunk(geometry, radius, o[lo:lo + step], d[lo:lo + step])
             for lo in range(0, n, step)]
    return Hits(*(np.concatenate([getattr(p, k) for p in parts]) for k in Hits.__annotations__))


@dataclass(frozen=True)
class Features:
    """Edge and vertex data of a world, prepared for one disk radius.

    ``mat`` turns the per-ray row ``[dx, dy, ox, oy, cross(o, d), 1]`` into, per edge, the four
    quantities that must all be >= 0 for a hit (approach, the two ends of the edge parameter,
    origin not behind the edge line) and the time numerator: one matrix product does the maths.
    """

    mat: np.ndarray  # (6, 5 * E)
    n_edges: int
    ax: np.ndarray  # shifted edge starts and edge vectors, for the exact distance of the winner
    ay: np.ndarray
    ex: np.ndarray
    ey: np.ndarray
    normals: np.ndarray
    vx: np.ndarray  # reflex vertices (disk radius > 0 only)
    vy: np.ndarray
    vid: np.ndarray  # the edge each vertex starts
    vprev: np.ndarray  # the edge each vertex ends
    ttol: float
    corners: tuple[tuple[float, float, int, int], ...]  # (vx, vy, vid, vprev) as Python numbers


def features(world: World, radius: float) -> Features:
    """The edge and vertex data of ``world`` prepared for disks of ``radius`` (cached on the
    world): what every query here, and the JAX ray cast (`bounce_gym.jax.raycast`), reads."""
    cache = world.__dict__.setdefault("_raycast_features", {})
    feats = cache.get(radius)
    if feats is None:
        start = world.edge_start + radius * world.normals
        ax, ay = start[:, 0], start[:, 1]
        ex, ey = (world.edge_end - world.edge_start).T
        zero, one = np.zeros_like(ax), np.ones_like(ax)
        utol = world.tol / world.lengths
        ttol = world.tol
        # columns of the ray row: dx, dy, ox, oy, cross(o, d), 1
        den = np.stack([ey, -ex, zero, zero, zero, zero])          # cross(d, e)
        num_t = np.stack([zero, zero, -ey, ex, zero, ax * ey - ay * ex])  # cross(a - o, e)
        num_u = np.stack([-ay, ax, zero, zero, -one, zero])         # cross(a - o, d)
        approach = den - 1e-12 * np.stack([zero, zero, zero, zero, zero, world.lengths])
        # num_t / length is the signed distance of the origin from the (shifted) edge line:
        # accept origins up to ``tol`` behind it, so grazing rays from a robot resting on a wall
        # (rounded a hair outside) still register the wall at distance 0.
        behind = num_t + ttol * np.stack([zero, zero, zero, zero, zero, world.lengths])
        mat = np.concatenate(
            [approach, num_u + utol * den, (1 + utol) * den - num_u, behind, num_t], axis=1
        )
        vid = np.flatnonzero(world.reflex) if radius > 0 else np.empty(0, dtype=np.int64)
        verts = world.edge_start[vid]
        prev = np.arange(world.n_edges) - 1
        for ring in np.unique(world.edge_ring):
            idx = np.flatnonzero(world.edge_ring == ring)
            prev[idx[0]] = idx[-1]
        feats = Features(
            mat=np.ascontiguousarray(mat), n_edges=len(ax), ax=ax.copy(), ay=ay.copy(),
            ex=ex.copy(), ey=ey.copy(), normals=world.normals,
            vx=verts[:, 0].copy(), vy=verts[:, 1].copy(), vid=vid, vprev=prev[vid], ttol=ttol,
            corners=tuple(zip(*verts.T.tolist(), vid.tolist(), prev[vid].tolist(), strict=True)),
        )
        cache[radius] = feats
    return feats


def _first_hit_chunk(f: Features, radius: float, o: np.ndarray, d: np.ndarray) -> Hits:
    n, m = len(o), f.n_edges
    ray = np.empty((n, 6))
    ray[:, 0:2] = d
    ray[:, 2:4] = o
    ray[:, 4] = o[:, 0] * d[:, 1] - o[:, 1] * d[:, 0]
    ray[:, 5] = 1.0
    q = (ray @ f.mat).reshape(n, 5, m)
    ok = q[:, :4].min(axis=1) >= 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(ok, q[:, 4] / q[:, 0], np.inf)
    edge = np.argmin(t, axis=1)
    rows = np.arange(n)
    distance = t[rows, edge]
    # the product form can lose a few ulps to cancellation: recompute the winner directly
    found = np.isfinite(distance)
    if found.any():
        k = edge[found]
        wx, wy = f.ax[k] - o[found, 0], f.ay[k] - o[found, 1]
        ex, ey = f.ex[k], f.ey[k]
        distance[found] = (wx * ey - wy * ex) / (d[found, 0] * ey - d[found, 1] * ex)
    normal = f.normals[edge]
    vertex = np.full(n, -1, dtype=np.int64)
    if len(f.vx):
        cx = o[:, 0:1] - f.vx
        cy = o[:, 1:2] - f.vy
        b = cx * d[:, 0:1] + cy * d[:, 1:2]
        c = cx * cx + cy * cy - radius * radius
        disc = b * b - c
        with np.errstate(invalid="ignore"):
            tv = -b - np.sqrt(disc)
        # moving towards the vertex (not grazing it), outside its circle or inside by <= tol
        okv = (disc > (GRAZE * radius) ** 2) & (b < 0) & (c >= -2.0 * radius * f.ttol)
        tv = np.where(okv, np.maximum(tv, 0.0), np.inf)
        kv = np.argmin(tv, axis=1)
        bestv = tv[rows, kv]
        use = bestv < distance
        if np.any(use):
            distance[use] = bestv[use]
            vid = f.vid[kv[use]]
            edge[use] = vid
            vertex[use] = vid
            rel = o[use] + bestv[use, None] * d[use] - np.column_stack((f.vx, f.vy))[kv[use]]
            normal[use] = rel / np.hypot(rel[:, 0], rel[:, 1])[:, None]
    edge[~np.isfinite(distance)] = -1
    np.maximum(distance, 0.0, out=distance)
    return Hits(distance, edge, vertex, normal)


def _first_hit_one(f: Features, radius: float, o: np.ndarray, d: np.ndarray) -> Hits:
    """`_first_hit_chunk` for a single ray, as `_cast_one` computes it."""
    distance, edge, vertex, nx, ny = _cast_one(f, radius, float(o[0]), float(o[1]), float(d[0]),
                                               float(d[1]))
    return Hits(np.array([distance]), np.array([edge]), np.array([vertex]), np.array([[nx, ny]]))


def first_hit_scalar(world: World, ox: float, oy: float, dx: float, dy: float,
                     radius: float = 0.0, skip: frozenset = frozenset()
                     ) -> tuple[float, int, int, float, float]:
    """`first_hit` of one ray from (ox, oy) along (dx, dy), in plain Python numbers:
    ``(distance, edge, vertex, nx, ny)``, bit for bit the values `first_hit` returns (the
    single-robot hot path). The edges in ``skip``, and the reflex vertices at their ends, are
    left out (a robot already touching them)."""
    return _cast_one(features(world, radius), radius, ox, oy, dx, dy, skip)


def _cast_one(f: Features, radius: float, ox: float, oy: float, dx: float,
              dy: float, skip: frozenset = frozenset()) -> tuple[float, int, int, float, float]:
    """One ray against prepared features. The edge tests come from the same matrix product as
    `_first_hit_chunk`, so they round alike; the choice among edges is a Python loop, cheaper
    than half a dozen numpy calls on the few edges of a typical world."""
    n = f.n_edges
    q = (np.array([dx, dy, ox, oy, ox * dy - oy * dx, 1.0]) @ f.mat).tolist()
    # np.argmin over t = num / approach (inf where a test fails): the first minimum, or the
    # first NaN; edge 0 when every t is inf
    distance, edge = math.inf, 0
    for k in range(n):
        den = q[k]
        if skip and k in skip:
            continue
        if den >= 0.0 and q[n + k] >= 0.0 and q[2 * n + k] >= 0.0 and q[3 * n + k] >= 0.0:
            num = q[4 * n + k]
            if den == 0.0:  # numpy's x / 0: ±inf, or NaN for 0 / 0
                t = math.copysign(math.inf, num) * math.copysign(1.0, den) if num else math.nan
            else:
                t = num / den
            if t != t:
                distance, edge = t, k
                break
            if t < distance:
                distance, edge = t, k
    nx, ny = f.normals[edge].tolist()
    vertex = -1
    if math.isfinite(distance):
        wx, wy = float(f.ax[edge]) - ox, float(f.ay[edge]) - oy
        ex, ey = float(f.ex[edge]), float(f.ey[edge])
        distance = (wx * ey - wy * ex) / (dx * ey - dy * ex)
    else:
        edge = -1
    if len(f.vx):
        vertex_hit = _vertex_hit_loop if len(f.vx) <= LOOP_VERTICES else _vertex_hit_numpy
        t, kv = vertex_hit(f, radius, ox, oy, dx, dy, skip)
        if t < distance:
            vx, vy, edge, _ = f.corners[kv]
            distance, vertex = t, edge
            px, py = ox + distance * dx - vx, oy + distance * dy - vy
            norm = math.hypot(px, py)
            nx, ny = px / norm, py / norm
    return max(distance, 0.0), edge, vertex, nx, ny


def _vertex_hit_loop(f: Features, radius: float, ox: float, oy: float, dx: float, dy: float,
                     skip: frozenset) -> tuple[float, int]:
    """The first reflex vertex the disk hits, in plain floats: (distance, index into the
    vertices), (inf, 0) if none — the same operations, rounded alike, as `_vertex_hit_numpy`,
    cheaper on the few vertices of a typical world."""
    graze, inside = (GRAZE * radius) ** 2, -2.0 * radius * f.ttol
    r2 = radius * radius
    best, kv = math.inf, 0
    for j, (vx, vy, start, end) in enumerate(f.corners):
        cx, cy = ox - vx, oy - vy
        b = cx * dx + cy * dy
        c = cx * cx + cy * cy - r2
        disc = b * b - c
        if disc > graze and b < 0 and c >= inside and not (skip and (start in skip or end in skip)):
            t = max(-b - math.sqrt(disc), 0.0)
            if t < best:
                best, kv = t, j
    return best, kv


def _vertex_hit_numpy(f: Features, radius: float, ox: float, oy: float, dx: float, dy: float,
                      skip: frozenset) -> tuple[float, int]:
    """`_vertex_hit_loop` with numpy, for worlds of many reflex vertices."""
    cx, cy = ox - f.vx, oy - f.vy
    b = cx * dx + cy * dy
    c = cx * cx + cy * cy - radius * radius
    disc = b * b - c
    with np.errstate(invalid="ignore"):
        tv = np.where((disc > (GRAZE * radius) ** 2) & (b < 0) & (c >= -2.0 * radius * f.ttol),
                      np.maximum(-b - np.sqrt(disc), 0.0), np.inf)
    if skip:  # a vertex starts its edge and ends the previous one of its ring
        for j, (_, _, start, end) in enumerate(f.corners):
            if start in skip or end in skip:
                tv[j] = np.inf
    kv = int(np.argmin(tv))
    return float(tv[kv]), kv
