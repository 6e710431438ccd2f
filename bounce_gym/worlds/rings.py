"""The rings of a `World`: checked one at a time for the messages, all at once for speed.

`World` checks its outer ring with `check_ring_shape` and its holes with `checked_holes`, which
screens every hole at once (numpy over the concatenated vertices, one vectorised shapely call)
and re-checks only the holes the screen flags with `check_ring_shape`, so a map with thousands
of holes (a large grid map) is checked in about linear time with the same messages, reported
for the same hole, as checking the holes one after another. The screen flags a superset of the
faults (its area test has a margin for rounding), never fewer.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from shapely.geometry import LinearRing, Polygon

from bounce_gym.errors import InvalidWorldError

#: Rings whose signed area is within this fraction of the sum of its shoelace terms are
#: treated as nearly flat: screened by `check_ring_shape` and oriented by `signed_area`.
_FLAT = 1e-9


def as_ring(points: object, label: str) -> np.ndarray:
    """``points`` as an (n, 2) float array of at least 3 finite vertices (a closing vertex equal
    to the first is dropped)."""
    try:
        ring = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidWorldError(f"{label}: vertices must be a sequence of (x, y) numbers") from exc
    if ring.ndim != 2 or ring.shape[1] != 2:
        raise InvalidWorldError(
            f"{label}: vertices must have shape (n, 2), got shape {ring.shape}"
        )
    if len(ring) > 1 and ring[0, 0] == ring[-1, 0] and ring[0, 1] == ring[-1, 1]:
        ring = ring[:-1]  # a closing vertex equal to the first is the usual GeoJSON habit
    if len(ring) < 3:
        raise InvalidWorldError(f"{label}: a ring needs at least 3 vertices, got {len(ring)}")
    if not np.all(np.isfinite(ring)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(ring), axis=1))[0])
        raise InvalidWorldError(f"{label}: vertex {bad} is not finite: {ring[bad].tolist()}")
    return ring


def signed_area(ring: np.ndarray) -> float:
    """Shoelace area, positive for a counter-clockwise ring. Coordinates are taken relative to
    the first vertex, so a small ring far from the origin (map coordinates in metres of a
    projected system) keeps its digits instead of cancelling products of huge numbers."""
    rel = ring - ring[0]
    x, y = rel[:, 0], rel[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def check_ring_shape(ring: np.ndarray, label: str, tol: float) -> None:
    """Reject zero-length edges, repeated vertices, spikes and self-intersections."""
    nxt = np.roll(ring, -1, axis=0)
    lengths = np.hypot(*(nxt - ring).T)
    if np.any(lengths <= tol):
        k = int(np.argmax(lengths <= tol))
        raise InvalidWorldError(
            f"{label}: zero-length edge between vertices {k} and {(k + 1) % len(ring)} "
            f"at {ring[k].tolist()} (repeated vertex)"
        )
    _, first, counts = np.unique(ring, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        k = int(first[np.argmax(counts > 1)])
        raise InvalidWorldError(f"{label}: vertex {ring[k].tolist()} is repeated")
    t_out = (nxt - ring) / lengths[:, None]
    t_in = np.roll(t_out, 1, axis=0)
    cross = t_in[:, 0] * t_out[:, 1] - t_in[:, 1] * t_out[:, 0]
    dot = np.sum(t_in * t_out, axis=1)
    spikes = (np.abs(cross) <= 1e-12) & (dot < 0)
    if np.any(spikes):
        k = int(np.argmax(spikes))
        raise InvalidWorldError(
            f"{label}: collinear-degenerate vertex {k} at {ring[k].tolist()}: "
            "the boundary folds back on itself"
        )
    if not LinearRing(ring).is_simple:
        reason = shapely.is_valid_reason(Polygon(ring))
        raise InvalidWorldError(f"{label}: ring self-intersects ({reason})")
    if abs(signed_area(ring)) <= tol * tol:
        raise InvalidWorldError(f"{label}: ring has zero area (all vertices collinear)")


def checked_holes(holes: Sequence, tol: float) -> list[np.ndarray]:
    """The holes as clockwise (n, 2) arrays, each checked as `as_ring` and `check_ring_shape`
    would (the first faulty hole raises, with the same message)."""
    rings: list[np.ndarray] = []
    error = None
    for k, hole in enumerate(holes):
        try:
            rings.append(as_ring(hole, f"hole {k}"))
        except InvalidWorldError as exc:
            error = exc  # raised after the holes before it, as when checked one by one
            break
    if rings:
        _check_shapes(rings, tol)
    if error is not None:
        raise error
    return _clockwise(rings)


class _Links:
    """The vertices of many rings concatenated: each vertex's ring and its neighbours."""

    def __init__(self, rings: Sequence[np.ndarray]) -> None:
        sizes = np.array([len(r) for r in rings])
        self.points = np.concatenate(rings)
        self.first = np.cumsum(sizes) - sizes
        self.last = self.first + sizes - 1
        self.ring = np.repeat(np.arange(len(rings)), sizes)
        index = np.arange(len(self.points))
        self.next, self.prev = index + 1, index - 1
        self.next[self.last] = self.first
        self.prev[self.first] = self.last

    def per_ring(self, values: np.ndarray) -> np.ndarray:
        return np.bincount(self.ring, weights=values, minlength=len(self.first))

    def areas(self) -> tuple[np.ndarray, np.ndarray]:
        """Each ring's shoelace area (as `signed_area`, up to rounding) and the sum of the
        magnitudes of its terms (the scale of that rounding)."""
        rel = self.points - self.points[self.first][self.ring]
        a = rel[:, 0] * rel[self.next, 1]
        b = rel[self.next, 0] * rel[:, 1]
        return 0.5 * self.per_ring(a - b), self.per_ring(np.abs(a) + np.abs(b))


def _check_shapes(rings: list[np.ndarray], tol: float) -> None:
    """Raise the error of the first hole `check_ring_shape` refuses, re-checking only the holes
    the vectorised screen flags."""
    links = _Links(rings)
    p, nxt, prev = links.points, links.next, links.prev
    step = p[nxt] - p
    lengths = np.hypot(step[:, 0], step[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):  # zero lengths are flagged already
        t_out = step / lengths[:, None]
    t_in = t_out[prev]
    cross = t_in[:, 0] * t_out[:, 1] - t_in[:, 1] * t_out[:, 0]
    dot = np.sum(t_in * t_out, axis=1)
    flagged = links.per_ring((lengths <= tol) | ((np.abs(cross) <= 1e-12) & (dot < 0))) > 0
    order = np.lexsort((p[:, 1], p[:, 0], links.ring))
    same = (links.ring[order][1:] == links.ring[order][:-1]) & np.all(
        p[order][1:] == p[order][:-1], axis=1)
    flagged[links.ring[order][1:][same]] = True
    closed = np.insert(np.arange(len(p)), links.last + 1, links.first)
    flagged |= ~shapely.is_simple(shapely.linearrings(p[closed], indices=links.ring[closed]))
    area, scale = links.areas()
    flagged |= np.abs(area) <= tol * tol + _FLAT * scale
    for k in np.flatnonzero(flagged):
        check_ring_shape(rings[k], f"hole {k}", tol)


def _clockwise(rings: list[np.ndarray]) -> list[np.ndarray]:
    """The rings, each reversed if it runs counter-clockwise."""
    if not rings:
        return rings
    area, scale = _Links(rings).areas()
    flat = np.abs(area) <= _FLAT * scale
    area[flat] = [signed_area(rings[k]) for k in np.flatnonzero(flat)]
    return [r[::-1].copy() if a > 0 else r for r, a in zip(rings, area, strict=True)]


def edges(rings: Sequence[np.ndarray]) -> tuple[np.ndarray, ...]:
    """The directed edges of all rings: start and end points, ring index and whether the
    edge's start vertex is reflex (a right turn: free space is on the left)."""
    links = _Links(rings)
    p = links.points
    t_out = p[links.next] - p
    t_in = p - p[links.prev]
    cross = t_in[:, 0] * t_out[:, 1] - t_in[:, 1] * t_out[:, 0]
    scale = np.hypot(*t_in.T) * np.hypot(*t_out.T)
    return p, p[links.next], links.ring, cross < -1e-12 * scale


def check_holes(outer: np.ndarray, holes: list[np.ndarray]) -> None:
    """Every hole strictly inside the outer ring, and no two holes meeting; the first offender
    (by hole index, then pair) is reported. Vectorised: the pairs come from an R-tree query, so
    a map with many holes (a large grid map) is checked in about linear time, not in one test
    per pair of holes."""
    if not holes:
        return
    shell, shell_ring = Polygon(outer), LinearRing(outer)
    shapely.prepare(shell)
    shapely.prepare(shell_ring)
    sizes = [len(h) for h in holes]
    rings = shapely.linearrings(np.concatenate(holes), indices=np.repeat(np.arange(len(holes)),
                                                                         sizes))
    polys = shapely.polygons(rings)
    outside = ~shapely.contains(shell, polys)
    touching = shapely.intersects(shell_ring, rings)
    bad = np.flatnonzero(outside | touching)
    if len(bad):
        k = int(bad[0])
        where = "not inside the outer ring" if outside[k] else "touches the outer ring"
        raise InvalidWorldError(f"hole {k}: {where}")
    first, second = shapely.STRtree(polys).query(polys, predicate="intersects")
    later = first < second
    if later.any():
        i, j = min(zip(first[later].tolist(), second[later].tolist(), strict=True))
        what = "overlap" if polys[i].intersection(polys[j]).area > 0 else "touch"
        raise InvalidWorldError(f"holes {i} and {j} {what}; holes must be disjoint")
