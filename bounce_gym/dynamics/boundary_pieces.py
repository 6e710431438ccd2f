"""The boundary of a disk robot's configuration space as smooth pieces with arc length: the
coordinates of a bump-to-bump map (`bounce_gym.dynamics.bump_table`).

A robot of radius R touches the walls with its centre on the boundary of `World.eroded` (the
free space shrunk by R). Its rings are polygons: the walls shifted by R, joined around reflex
wall corners by chords of the arcs a disk's centre follows there. `BoundaryPieces` cuts every
ring at its **sharp vertices** — where the boundary turns by more than `BREAK` (the inside
corners of rooms, the tips of acute obstacles) — and keeps the rest whole: a straight wall, the
arc around an obstacle corner and the next wall form one piece, along which the bump map is
continuous except where the drive's target changes. A piece is parametrized by arc length s
from its first vertex (Birkhoff's coordinate of the billiard boundary); a ring with no sharp
vertex is one piece from its first vertex all the way round.

Points are mapped back to (piece, s) by projection onto the nearest ring segment among those a
grid lists near them (`project`, `bounce_gym.dynamics.segment_grid`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from bounce_gym.dynamics.segment_grid import SegmentGrid
from bounce_gym.worlds import World

#: A ring vertex where the boundary turns by more than this (radians) ends a piece: 20°, well
#: above the 6.4° between the chords of a disk's arc (`World.eroded`'s 16 chords per quarter
#: circle) and well below the 90° of a room's corner.
BREAK = math.radians(20.0)
#: Points within this many radii of the boundary are projected onto it exactly (the grid of
#: `bounce_gym.dynamics.segment_grid` lists the segments that near); contact points lie within
#: a few hundredths of a radius.
REACH = 0.1
#: the grid's cell side, in radii: small enough that a cell lists few of the short chords
#: around an obstacle corner (at most six on the lab maps)
CELL = 0.25


class BoundaryPieces:
    """The configuration-space boundary of a disk robot in a world, as pieces (module
    docstring).

    Attributes:
        start, end: (m, 2) the ring segments, free space on their left, ring by ring in order.
        normal: (m, 2) their inward unit normals.
        piece: (m,) the piece each segment belongs to.
        offset: (m,) the arc length of each segment's start along its piece.
        length: (P,) the length of every piece.
        first: (P,) the first segment of every piece (its segments follow in ring order).
    """

    def __init__(self, world: World, radius: float) -> None:
        self.world, self.radius = world, float(radius)
        starts, pieces, offsets, lengths, firsts = [], [], [], [], []
        count = 0
        for ring in _rings(world.eroded(radius)):
            a, b = ring, np.roll(ring, -1, axis=0)
            seg = b - a
            angle = np.arctan2(seg[:, 1], seg[:, 0])
            turn = np.abs(np.mod(angle - np.roll(angle, 1) + math.pi, 2 * math.pi) - math.pi)
            cut = np.flatnonzero(turn > BREAK)
            first = int(cut[0]) if len(cut) else 0
            order = np.roll(np.arange(len(a)), -first)  # start the ring at a sharp vertex
            sharp = np.isin(order, cut) | (np.arange(len(order)) == 0)
            label = np.cumsum(sharp) - 1 + count
            seg_len = np.hypot(seg[order, 0], seg[order, 1])
            cum = np.cumsum(seg_len)
            piece_start = np.flatnonzero(sharp)
            base = np.repeat(cum[piece_start] - seg_len[piece_start],
                             np.diff(np.append(piece_start, len(order))))
            starts.append(a[order])
            pieces.append(label)
            offsets.append(cum - seg_len - base)
            lengths.append(np.add.reduceat(seg_len, piece_start))
            firsts.append(sum(len(s) for s in starts[:-1]) + piece_start)
            count += len(piece_start)
        self.start = np.concatenate(starts)
        ring_end = [np.roll(s, -1, axis=0) for s in starts]
        self.end = np.concatenate(ring_end)
        self.piece = np.concatenate(pieces)
        self.offset = np.concatenate(offsets)
        self.length = np.concatenate(lengths)
        self.first = np.concatenate(firsts)
        tangent = self.end - self.start
        seg_len = np.hypot(tangent[:, 0], tangent[:, 1])
        tangent = tangent / seg_len[:, None]
        self.normal = np.column_stack((-tangent[:, 1], tangent[:, 0]))
        self._seg_len = seg_len
        #: each segment's neighbours along its ring (the normals at vertices average them)
        ring_size = np.concatenate([np.full(len(s), len(s)) for s in starts])
        ring_first = np.concatenate([np.full(len(s), sum(len(t) for t in starts[:i]))
                                     for i, s in enumerate(starts)])
        local = np.arange(len(self.start)) - ring_first
        self._before = ring_first + np.mod(local - 1, ring_size)
        self._after = ring_first + np.mod(local + 1, ring_size)
        self._grid = SegmentGrid(self.start, self.end, CELL * radius, REACH * radius)

    @property
    def n_pieces(self) -> int:
        return len(self.length)

    def locate(self, piece: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The points at arc length ``s`` along ``piece`` and the inward normals there (at a
        vertex between two segments, the mean of both normals, normalised)."""
        piece = np.asarray(piece, dtype=np.int64)
        s = np.asarray(s, dtype=np.float64)
        # segments run piece by piece, in order along each: their starts along all pieces
        # laid end to end increase, so the segment holding s is found by bisection
        base = np.concatenate(([0.0], np.cumsum(self.length)[:-1]))
        along = base[self.piece] + self.offset
        last = np.append(self.first[1:], len(self.start)) - 1
        seg = np.clip(np.searchsorted(along, base[piece] + s, side="right") - 1,
                      self.first[piece], last[piece])
        t = np.clip((s - self.offset[seg]) / self._seg_len[seg], 0.0, 1.0)
        point = self.start[seg] + t[:, None] * (self.end[seg] - self.start[seg])
        normal = self.normal[seg].copy()
        at_start = t <= 1e-12
        at_end = t >= 1.0 - 1e-12
        for mask, other in ((at_start, self._before), (at_end, self._after)):
            both = normal[mask] + self.normal[other[seg[mask]]]
            normal[mask] = both / np.hypot(both[:, 0], both[:, 1])[:, None]
        return point, normal

    def project(self, points: np.ndarray) -> Projection:
        """The nearest boundary point of each point (n, 2) (`Projection`); a point farther
        than `REACH` radii from the boundary may read as at distance inf."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        candidates = self._grid.near(points)
        _, dist, t = self._grid.closest(points, candidates)
        pick = np.argmin(dist, axis=1)
        rows = np.arange(len(points))
        best_d, best_t = dist[rows, pick], t[rows, pick]
        # the padding segment (beyond the reach of every segment) reads as segment 0, far away
        best_seg = candidates[rows, pick]
        best_d = np.where(best_seg < len(self.start), best_d, np.inf)
        best_seg = np.where(best_seg < len(self.start), best_seg, 0)
        s = self.offset[best_seg] + best_t * self._seg_len[best_seg]
        return Projection(self.piece[best_seg], s, best_d, self.normal[best_seg])


@dataclass(frozen=True)
class Projection:
    """Points projected onto the boundary (`BoundaryPieces.project`), one entry per point.

    Attributes:
        piece, s: the piece of the nearest boundary point and its arc length along the piece.
        distance: the distance to it.
        normal: (n, 2) the inward normal of its segment.
    """

    piece: np.ndarray
    s: np.ndarray
    distance: np.ndarray
    normal: np.ndarray


def _rings(region) -> list[np.ndarray]:
    """The rings of a shapely (Multi)Polygon as (k, 2) vertex arrays without the closing
    vertex, oriented with the region on their left."""
    polygons = region.geoms if isinstance(region, MultiPolygon) else [region]
    out = []
    for polygon in polygons:
        if not isinstance(polygon, Polygon) or polygon.is_empty:
            continue
        polygon = orient(polygon, sign=1.0)
        for ring in (polygon.exterior, *polygon.interiors):
            out.append(np.asarray(ring.coords, dtype=np.float64)[:-1])
    return out
