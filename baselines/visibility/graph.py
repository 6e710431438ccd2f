"""Bounce visibility graph (BVG), maximal safe intervals (Prop. 2) and G_safe (Nilles et al. 2021,
§5 and §7).

* `entirely_visible` / `visibility_matrix`: Def. 6. Two segments are entirely visible iff the
  convex hull of their union lies in P (the hull is the union of all segments joining them), which
  also rejects holes inside the hull (docs/choices/visibility.md, "Holes inside the convex hull"). Each segment
  must face the other (closed left side of the other's supporting line); segments on one supporting
  line are never adjacent. ``closed=True`` (default; docs/choices/visibility.md, "Closed visibility"): grazing
  a vertex or sliding along collinear boundary counts as visible. ``closed=False``: no vertex of P'
  other than the four end points may touch the hull.
* `safe_interval`: Prop. 2 with ``atan2`` angles; θ_r = 0 for a shared vertex v_{i+1} = v_j and
  θ_l = π for v_{j+1} = v_i.
* `bvg`, `safe_graph`: `networkx.DiGraph` over segment ids; G_safe arcs carry ``lo``, ``hi``,
  ``width`` and drop intervals narrower than ``w_min`` (docs/choices/visibility.md, "Tiny safe intervals are
  dropped").
* `reachability`: the §7.3–7.4 analysis (Prop. 5 unreachable nodes, SCCs, WCCs, sinks).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np
import shapely

from baselines.visibility.partition import (
    SIDE_TOL,
    VIS_REL,
    Partition,
    _touches_points,
    closed_region,
)

__all__ = [
    "SafeGraphReachability",
    "bvg",
    "entirely_visible",
    "reachability",
    "safe_graph",
    "safe_interval",
    "safe_intervals",
    "visibility_matrix",
    "weak_visibility_matrix",
]

#: Default width threshold (rad) of G_safe.
W_MIN = 1e-6


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1]


def _candidate_pairs(part: Partition) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j), i != j, that face each other and are not on one supporting line."""
    eps = part.tol
    a, b = part.start, part.end
    # height of every vertex above every segment's line: h[i, k] for point k over segment i
    h_start = _cross(part.tangent[:, None, :], a[None, :, :] - a[:, None, :])
    h_end = _cross(part.tangent[:, None, :], b[None, :, :] - a[:, None, :])
    up = (h_start >= -eps) & (h_end >= -eps)  # segment j on the closed left side of i
    on_line = (np.abs(h_start) <= eps) & (np.abs(h_end) <= eps)
    ok = up & up.T & ~on_line & ~on_line.T
    np.fill_diagonal(ok, False)
    i, j = np.nonzero(ok)
    keep = i < j
    return i[keep], j[keep]


def visibility_matrix(part: Partition, closed: bool | None = None) -> np.ndarray:
    """(m, m) symmetric boolean matrix of entire visibility (Def. 6) between P' segments."""
    closed = part.closed if closed is None else closed
    m = part.n
    out = np.zeros((m, m), dtype=bool)
    i, j = _candidate_pairs(part)
    if len(i):
        corners = np.stack((part.start[i], part.end[i], part.start[j], part.end[j]), axis=1)
        hulls = shapely.convex_hull(shapely.multipoints(corners))
        ok = shapely.covers(closed_region(part.world, part.tol), hulls)
        if not closed:
            ends = [corners[:, k] for k in range(4)]
            ok &= ~_touches_points(hulls, ends, part.start, part.tol)
        out[i[ok], j[ok]] = True
        out[j[ok], i[ok]] = True
    return out


def entirely_visible(part: Partition, i: int, j: int, closed: bool | None = None) -> bool:
    """Def. 6 for one pair of P' segments (see `visibility_matrix`)."""
    return bool(visibility_matrix(part, closed)[i, j])


def _angle_above(t, v, tol):
    """Angle of ``v`` counter-clockwise from the unit tangent ``t``, in [0, 2π); a ``v`` whose
    end lies within the length ``tol`` of t's line is on it (angle exactly 0 or π), so the
    result does not depend on where the polygon lies or on its units."""
    h = _cross(t, v)
    theta = np.arctan2(np.where(np.abs(h) <= tol, 0.0, h), _dot(t, v))
    return np.where(theta < 0.0, theta + 2 * np.pi, theta)


def _angles(a, b, c, d, t, tol):
    """θ_r, θ_l of Prop. 2 for arrays of e_i = (a, b) with unit tangent t, e_j = (c, d); ``tol``
    is the partition's length tolerance (shared end points, points on e_i's line)."""
    rc = c - b
    ld = d - a
    theta_r = np.where(np.hypot(rc[..., 0], rc[..., 1]) <= tol, 0.0, _angle_above(t, rc, tol))
    theta_l = np.where(np.hypot(ld[..., 0], ld[..., 1]) <= tol, np.pi, _angle_above(t, ld, tol))
    # a ray from e_i that heads below e_i's own supporting line: clamp to [0, π]
    return np.clip(theta_r, 0.0, np.pi), np.clip(theta_l, 0.0, np.pi)


def safe_interval(seg_i, seg_j, w_min: float = 0.0) -> tuple[float, float] | None:
    """Maximal safe interval [θ_r, θ_l] from ``seg_i`` to ``seg_j`` (Prop. 2), or None.

    Args:
        seg_i, seg_j: ``((x0, y0), (x1, y1))`` directed segments with free space on the left
            (P' segments ``(v_i, v_{i+1})``, ``(v_j, v_{j+1})``), assumed entirely visible.
        w_min: intervals narrower than this are dropped (0 keeps the case-3 singleton).

    Returns:
        ``(θ_r, θ_l)`` in radians, measured counter-clockwise from seg_i's tangent, or None when
        θ_l < θ_r (case 2) or the width is below ``w_min``.
    """
    a, b = (np.asarray(p, dtype=np.float64) for p in seg_i)
    c, d = (np.asarray(p, dtype=np.float64) for p in seg_j)
    length = float(np.hypot(*(b - a)))
    tol = VIS_REL * max(length, float(np.hypot(*(d - c))))
    theta_r, theta_l = _angles(a, b, c, d, (b - a) / length, tol)
    theta_r, theta_l = float(theta_r), float(theta_l)
    # θ_l = θ_r up to the angle that tol subtends at the nearer far end (c from b, d from a)
    reach = [r for r in (float(np.hypot(*(c - b))), float(np.hypot(*(d - a)))) if r > tol]
    angle_tol = tol / min(reach) if reach else 0.0
    if theta_l - theta_r < max(w_min, 0.0) - angle_tol:
        return None
    if abs(theta_l - theta_r) <= angle_tol:
        theta_l = theta_r = 0.5 * (theta_l + theta_r)
    return theta_r, theta_l


def safe_intervals(part: Partition, i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised Prop. 2 angles (θ_r, θ_l) for arcs i -> j of P' (no visibility test)."""
    i, j = np.asarray(i), np.asarray(j)
    shared = part.tol
    return _angles(part.start[i], part.end[i], part.start[j], part.end[j], part.tangent[i],
                   shared)


def _group_pairs(group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (x, y), x < y, of rows of one group (``group`` sorted), ordered by x then y."""
    n = len(group)
    end = np.searchsorted(group, group, side="right")
    first = np.arange(n) + 1
    reps = np.maximum(end - first, 0)
    x = np.repeat(np.arange(n), reps)
    offset = np.arange(len(x)) - np.repeat(np.cumsum(reps) - reps, reps)
    return x, np.repeat(first, reps) + offset


def _meet(p0, p1, q0, q1) -> tuple[np.ndarray, np.ndarray]:
    """Parameter along q0->q1 of its intersection with the line p0-p1, and whether the lines
    are not parallel (arrays of points)."""
    dp, dq = p1 - p0, q1 - q0
    den = _cross(dp, dq)
    ok = np.abs(den) > SIDE_TOL * np.hypot(dp[:, 0], dp[:, 1]) * np.hypot(dq[:, 0], dq[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        return _cross(p0 - q0, dp) / -den, ok


def _weak_candidates(part: Partition, ii: np.ndarray, jj: np.ndarray, hit_pair: np.ndarray,
                     hit_vertex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parameters (s, u) of candidate sight lines p = a + s(b - a), q = c + u(d - c) of all
    pairs (ii[k], jj[k]) at once; ``hit_pair``/``hit_vertex`` list the P' vertices w near each
    pair's hull. Returns (pair index k, (s, u)) grouped by k.

    If the closed set of visible pairs is non-empty, one of its corners is a candidate: both
    end points fixed, one end point fixed and the line through a vertex ``w`` of P', or the line
    through two vertices (each constraint is "s or u at a bound" or "passes through w").
    Within a pair: the four corners, then per vertex w the lines from a, b, c, d through it,
    then the lines through two vertices.
    """
    a, b, c, d = part.start[ii], part.end[ii], part.start[jj], part.end[jj]
    n_pairs = len(ii)
    keys = [np.repeat(np.arange(n_pairs), 4)]
    params = [np.tile([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0]], (n_pairs, 1))]
    order = np.argsort(hit_pair, kind="stable")
    k, w = hit_pair[order], part.start[hit_vertex[order]]
    lines, kept = [], []
    for fixed, p, q0, q1, s_free in ((0.0, a, c, d, False), (1.0, b, c, d, False),
                                     (0.0, c, a, b, True), (1.0, d, a, b, True)):
        p = p[k]
        t, ok = _meet(p, w, q0[k], q1[k])
        ok &= np.hypot(*(w - p).T) > part.tol
        bound = np.full(len(t), fixed)
        lines.append(np.column_stack((t, bound) if s_free else (bound, t)))
        kept.append(ok)
    kept = np.stack(kept, axis=1).ravel()  # per vertex w: the lines from a, b, c, d
    keys.append(np.repeat(k, 4)[kept])
    params.append(np.stack(lines, axis=1).reshape(-1, 2)[kept])
    x, y = _group_pairs(k)
    kx, w1, w2 = k[x], w[x], w[y]
    s_, ok_s = _meet(w1, w2, a[kx], b[kx])
    u, ok_u = _meet(w1, w2, c[kx], d[kx])
    keys.append(kx[ok_s & ok_u])
    params.append(np.column_stack((s_, u))[ok_s & ok_u])
    keys, params = np.concatenate(keys), np.concatenate(params)
    order = np.argsort(keys, kind="stable")
    keys, params = keys[order], params[order]
    slack = part.tol / np.column_stack((part.length[ii], part.length[jj]))[keys]
    ok = (params >= -slack).all(axis=1) & (params <= 1 + slack).all(axis=1)
    return keys[ok], np.clip(params[ok], 0.0, 1.0)


def _sight_lines(part: Partition, i: np.ndarray, j: np.ndarray, st: np.ndarray):
    """End points p on e_i, q on e_j of the lines with parameters ``st``, and whether each line
    leaves both segments into free space (far end strictly left of the supporting line)."""
    a, c = part.start[i], part.start[j]
    p = a + st[:, :1] * (part.end[i] - a)
    q = c + st[:, 1:] * (part.end[j] - c)
    eps = part.tol
    good = (_cross(part.tangent[i], q - a) > eps) & (_cross(part.tangent[j], p - c) > eps)
    return p, q, good


def _group_means(group: np.ndarray, rows: np.ndarray, n_groups: int) -> tuple[np.ndarray,
                                                                              np.ndarray]:
    """Mean of the rows of every non-empty group (``group`` sorted), summed in row order as
    ``np.mean(axis=0)`` does; returns (groups, means)."""
    counts = np.bincount(group, minlength=n_groups)
    groups = np.flatnonzero(counts)
    first = np.searchsorted(group, groups)
    total = rows[first].copy()
    for r in range(1, int(counts.max(initial=0))):
        more = counts[groups] > r
        total[more] += rows[first[more] + r]
    return groups, total / counts[groups][:, None]


def _unique_rows(group: np.ndarray, st: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct (group, s, u) rows, sorted by group."""
    order = np.lexsort((st[:, 1], st[:, 0], group))
    group, st = group[order], st[order]
    new = np.ones(len(group), dtype=bool)
    new[1:] = (group[1:] != group[:-1]) | (st[1:] != st[:-1]).any(axis=1)
    return group[new], st[new]


def _open_sight(part: Partition, ii: np.ndarray, jj: np.ndarray, k: np.ndarray, st: np.ndarray,
                region, tree: shapely.STRtree) -> np.ndarray:
    """Pairs k whose line with parameters ``st`` leaves both segments into free space, lies in
    the closed free space and passes no P' vertex but its own end points (open sight lines)."""
    p, q, good = _sight_lines(part, ii[k], jj[k], st)
    k, p, q = k[good], p[good], q[good]
    lines = shapely.linestrings(np.stack((p, q), axis=1))
    inside = shapely.covers(region, lines)
    k, lines, p, q = k[inside], lines[inside], p[inside], q[inside]
    return k[~_touches_points(lines, [p, q], part.start, part.tol, tree)]


def weak_visibility_matrix(part: Partition, closed: bool | None = None) -> np.ndarray:
    """(m, m) symmetric matrix of Def. 5 visibility: some point of e_i sees some point of e_j.

    The sight line must leave each segment into free space (its far end strictly left of the
    segment's supporting line), so segments on one line, or meeting only at a reflex vertex, are
    not adjacent. ``closed=True``: exact, via the corner candidates of `_weak_candidates`.
    ``closed=False`` (Def. 5 with open segments and the interior of P) is approximated by testing
    the midpoints of pairs of closed-visible candidates, and their mean, with open sight lines.
    All pairs are tested together (one array of candidate lines, one call per predicate).
    """
    closed = part.closed if closed is None else closed
    m, eps = part.n, part.tol
    a, b = part.start, part.end
    h_start = _cross(part.tangent[:, None, :], a[None, :, :] - a[:, None, :])
    h_end = _cross(part.tangent[:, None, :], b[None, :, :] - a[:, None, :])
    some_up = (h_start > eps) | (h_end > eps)
    ok = some_up & some_up.T
    np.fill_diagonal(ok, False)
    ii, jj = np.nonzero(np.triu(ok))
    out = np.zeros((m, m), dtype=bool)
    if len(ii) == 0:
        return out
    corners = np.stack((a[ii], b[ii], a[jj], b[jj]), axis=1)
    hulls = shapely.convex_hull(shapely.multipoints(corners))
    tree = shapely.STRtree(shapely.points(part.start))
    hit_pair, hit_vertex = tree.query(hulls, predicate="dwithin", distance=eps)
    k, st = _weak_candidates(part, ii, jj, hit_pair, hit_vertex)
    p, q, good = _sight_lines(part, ii[k], jj[k], st)
    k, st = k[good], st[good]
    region = closed_region(part.world, eps)
    vis = shapely.covers(region, shapely.linestrings(np.stack((p[good], q[good]), axis=1)))
    k, st = k[vis], st[vis]
    seen = np.zeros(len(ii), dtype=bool)
    if closed:
        seen[k] = True
    else:
        # midpoints (x + y) / 2 of the closed-visible candidates of a pair and their mean, with
        # open sight lines. Duplicate candidates and the order of x, y add no midpoint; the
        # candidates themselves and the means go first, the other midpoints only for the pairs
        # still unseen.
        groups, means = _group_means(k, st, len(ii))
        k, st = _unique_rows(k, st)
        seen[_open_sight(part, ii, jj, np.concatenate((k, groups)),
                         np.concatenate((st, means)), region, tree)] = True
        x, y = _group_pairs(k)
        rest = ~seen[k[x]]
        x, y = x[rest], y[rest]
        seen[_open_sight(part, ii, jj, k[x], (st[x] + st[y]) / 2, region, tree)] = True
    out[ii[seen], jj[seen]] = True
    out[jj[seen], ii[seen]] = True
    return out


def _nodes(part: Partition) -> nx.DiGraph:
    g = nx.DiGraph(closed=part.closed)
    for k in range(part.n):
        g.add_node(k, start=tuple(part.start[k]), end=tuple(part.end[k]),
                   length=float(part.length[k]), ring=int(part.ring[k]), edge=int(part.edge[k]))
    return g


def bvg(part: Partition, closed: bool = False) -> nx.DiGraph:
    """Bounce visibility graph: the directed edge visibility graph of P' (Def. 5).

    Arcs i -> j and j -> i for every pair of segments with some line of sight between them
    (`weak_visibility_matrix`). The arcs carry no guarantee (docs/choices/visibility.md, "The BVG's arcs carry
    no guarantee"); plan with `safe_graph`,
    whose arcs need entire visibility (Def. 6).

    ``closed=False`` (default) is Def. 5 as stated: open segments, sight lines in the interior of
    P; it reproduces the arc lists of the authors' test polygons. ``closed=True`` also counts sight
    lines that graze vertices, even when they are isolated (e.g. a single grazing line ending at a
    corner).
    """
    vis = weak_visibility_matrix(part, closed)
    g = _nodes(part)
    g.graph["closed"] = bool(closed)
    g.add_edges_from(zip(*(x.tolist() for x in np.nonzero(vis)), strict=True))
    return g


def safe_graph(part: Partition, w_min: float = W_MIN, closed: bool | None = None) -> nx.DiGraph:
    """G_safe: BVG arcs with a non-empty safe interval of width >= ``w_min``.

    Arc attributes: ``lo`` = θ_r, ``hi`` = θ_l, ``width`` = θ_l − θ_r (radians). Intervals are
    stored closed; their end rays hit vertices, so sample strictly inside (docs/choices/visibility.md,
    "Sample strictly inside a safe interval").
    """
    vis = visibility_matrix(part, closed)
    i, j = np.nonzero(vis)
    lo, hi = safe_intervals(part, i, j)
    width = hi - lo
    keep = width >= w_min
    g = _nodes(part)
    g.graph["closed"] = part.closed if closed is None else bool(closed)
    g.graph["w_min"] = w_min
    for a, b, x, y, w in zip(i[keep].tolist(), j[keep].tolist(), lo[keep].tolist(),
                             hi[keep].tolist(), width[keep].tolist(), strict=True):
        g.add_edge(a, b, lo=x, hi=y, width=w)
    return g


@dataclass(frozen=True)
class SafeGraphReachability:
    """§7.3–7.4 / Prop. 5 analysis of a G_safe.

    Attributes:
        unreachable: nodes with in-degree 0 (no safe action reaches them from another segment).
        unreachable_fraction: their total length over the perimeter of P.
        sccs: strongly connected components (sets of nodes), largest first.
        wccs: weakly connected components, largest first.
        sinks: nodes with out-degree 0.
        condensation: DAG of the SCCs (``mapping`` node attribute as in networkx).
    """

    unreachable: list[int]
    unreachable_fraction: float
    sccs: list[set[int]]
    wccs: list[set[int]]
    sinks: list[int]
    condensation: nx.DiGraph

    @property
    def n_sccs(self) -> int:
        return len(self.sccs)

    @property
    def n_wccs(self) -> int:
        return len(self.wccs)


def reachability(g: nx.DiGraph, part: Partition) -> SafeGraphReachability:
    """Unreachable nodes, their perimeter fraction, SCCs, WCCs and sinks of G_safe (§7.3–7.4)."""
    unreachable = sorted(k for k, d in g.in_degree() if d == 0)
    frac = float(part.length[unreachable].sum() / part.perimeter) if unreachable else 0.0
    sccs = sorted(nx.strongly_connected_components(g), key=lambda c: (-len(c), min(c)))
    wccs = sorted(nx.weakly_connected_components(g), key=lambda c: (-len(c), min(c)))
    sinks = sorted(k for k, d in g.out_degree() if d == 0)
    return SafeGraphReachability(unreachable, frac, sccs, wccs, sinks, nx.condensation(g, sccs))
