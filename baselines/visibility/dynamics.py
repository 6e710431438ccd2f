"""Dynamical properties of bouncing paths: transition maps, contraction and limit cycles.

Nilles, Ren, Becerra & LaValle, "A visibility-based approach to computing non-deterministic
bouncing strategies" (IJRR 2021), §6 (dynamical properties of paths: Defs. 8–13, Lemmas 2–3, Theorem
1, Prop. 4, Cors. 3–4) and §6.1 (limit cycles, Fig. 9), with the model of §3.

**Frames (§3).** A *segment* is a ``(2, 2)`` array ``[start, end]`` whose free space lies on its
left, exactly like a directed edge of a `World` (outer ring counter-clockwise, holes clockwise):
``t = (end − start)/ℓ``, ``n = t`` rotated by +90° (the inward normal), and the action ``θ ∈ (0, π)``
is the heading ``d(θ) = cos θ·t + sin θ·n``. Positions ``s`` on a segment are distances from its
start (the paper's "clockwise endpoint" v_i). `edge_segment` turns a world edge into a segment.

**Transition map (§6).** From ``p = v_i + s·t_i`` along ``d(θ)`` the supporting line of ``e_j`` is
met at ``μ(s, θ) = cross(p − v_j, d) / cross(t_j, d)`` (distance from ``v_j``). It is affine in
``s`` with slope ``∂μ/∂s = sin θ / sin(θ − γ) = −C`` (γ = direction of ``t_j`` relative to ``t_i``):
every transition reverses orientation, and ``C = |sin θ / sin(θ − γ)|`` (Def. 11, unified form:
docs/choices/visibility.md, "Contraction for non-adjacent edges") is independent of the position. `transition`,
`slope`, `interval_image`, `contraction`, `is_contracting`, `lemma2_threshold`, `contracting_range`
and `composite_contraction` (Def. 12) implement this; `composite_fixed_point` gives the fixed point
``μ* = A / (1 − (−1)^m C(F))`` of any closed edge sequence with per-stage actions.

**Fixed rule in convex polygons.** `lemma3_bound` (Lemma 3), `fixed_rule_cycle` (Theorem 1: the
fixed point ``d_FP`` on ``e_0`` and all contacts of the period-n limit cycle), the closed forms
`regular_ngon_fixed_point` and `rectangle_fixed_point`, `cor3_bound` and `iterations_to`
(Cor. 4, the paper's conservative ``⌈log(ε/(2ℓ))/log C⌉``; docs/choices/visibility.md,
"Corollary 4 is conservative"). `simulate_fixed_rule` runs the
exact point-robot fixed rule with `World.first_hit`, to check the analytic results.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from baselines.visibility.partition import SIDE_TOL
from bounce_gym.worlds import World

__all__ = [
    "CompositeCycle",
    "FixedRuleCycle",
    "FixedRuleTrace",
    "Lemma3Bound",
    "composite_contraction",
    "composite_fixed_point",
    "contracting_range",
    "contraction",
    "contraction_coefficient",
    "cor3_bound",
    "edge_segment",
    "fixed_rule_cycle",
    "hits_segment",
    "interior_angle",
    "interval_image",
    "is_contracting",
    "iterations_to",
    "lemma2_threshold",
    "lemma3_bound",
    "rectangle_fixed_point",
    "regular_ngon_fixed_point",
    "relative_direction",
    "sample_boundary",
    "simulate_fixed_rule",
    "slope",
    "transition",
    "transition_side",
]


# -- segments and frames ------------------------------------------------------------------------

def edge_segment(world: World, k: int) -> np.ndarray:
    """Edge ``k`` of ``world`` as a ``(2, 2)`` segment ``[v_k, v_{k+1}]`` (free space on its left)."""
    return np.array([world.edge_start[k], world.edge_end[k]], dtype=np.float64)


def _frame(seg: object) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(start, unit tangent t, left normal n, length) of a segment ``[start, end]``."""
    arr = np.asarray(seg, dtype=np.float64)
    if arr.shape != (2, 2) or not np.all(np.isfinite(arr)):
        raise ValueError(f"a segment is a finite (2, 2) array [start, end], got {arr.tolist()!r}")
    vec = arr[1] - arr[0]
    length = float(np.hypot(vec[0], vec[1]))
    if length <= 0.0:
        raise ValueError(f"zero-length segment {arr.tolist()!r}")
    t = vec / length
    return arr[0], t, np.array([-t[1], t[0]]), length


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _heading(t: np.ndarray, n: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """d(θ) = cos θ·t + sin θ·n, shape ``theta.shape + (2,)``."""
    theta = np.asarray(theta, dtype=np.float64)
    return np.cos(theta)[..., None] * t + np.sin(theta)[..., None] * n


def relative_direction(seg_i: object, seg_j: object) -> float:
    """γ ∈ (−π, π]: direction angle of ``t_j`` measured counter-clockwise from ``t_i``."""
    _, ti, _, _ = _frame(seg_i)
    _, tj, _, _ = _frame(seg_j)
    return float(math.atan2(ti[0] * tj[1] - ti[1] * tj[0], ti[0] * tj[0] + ti[1] * tj[1]))


def transition_side(seg_i: object, seg_j: object, tol: float = SIDE_TOL) -> str:
    """``"right"`` (γ ∈ (0, π): e_j is reached by turning toward the counter-clockwise-next side,
    small θ, as for the next edge of a convex polygon), ``"left"`` (γ ∈ (−π, 0)) or
    ``"parallel"`` (γ ∈ {0, π}: Def. 11's classification is undefined;
    docs/choices/visibility.md, "Contraction for non-adjacent edges"). Parallel means |sin γ| ≤ ``tol``, the
    partition's sidedness tolerance: tangents of a polygon far from the origin carry rounding
    errors far above 1e-12."""
    gamma = relative_direction(seg_i, seg_j)
    if abs(math.sin(gamma)) <= tol:
        return "parallel"
    return "right" if gamma > 0 else "left"


def interior_angle(seg_i: object, seg_j: object) -> float:
    """Def. 9: φ_{i,j}, the angle at the intersection O of the two supporting lines inside the
    triangle (O, x, f(x)). For adjacent edges of a polygon it is the interior angle at the shared
    vertex: φ = π − γ for a right transition and π + γ for a left one. Parallel lines give 0."""
    gamma = relative_direction(seg_i, seg_j)
    side = transition_side(seg_i, seg_j)
    if side == "parallel":
        return 0.0
    return math.pi - gamma if side == "right" else math.pi + gamma


# -- the transition map -------------------------------------------------------------------------

def transition(seg_from: object, seg_to: object, s: object, theta: object) -> np.ndarray:
    """The exact segment-to-segment map μ(s, θ) (§6), broadcast over ``s`` and ``theta``.

    ``s`` is the distance from the start of ``seg_from``; the result is the distance from the
    start of ``seg_to`` at which the ray of heading θ meets the *supporting line* of ``seg_to``.
    Whether that point is a real hit (in front of the robot, on the segment, from the free side)
    is `hits_segment`; occlusion by other edges is not checked here.
    """
    vi, ti, ni, _ = _frame(seg_from)
    vj, tj, _, _ = _frame(seg_to)
    s = np.asarray(s, dtype=np.float64)
    d = _heading(ti, ni, theta)
    p = vi + s[..., None] * ti
    with np.errstate(divide="ignore", invalid="ignore"):
        return _cross(p - vj, d) / _cross(tj, d)


def hits_segment(seg_from: object, seg_to: object, s: object, theta: object) -> np.ndarray:
    """Whether the ray from ``s`` with heading θ meets ``seg_to`` itself (0 ≤ μ ≤ ℓ_j), in front of
    the robot, arriving from ``seg_to``'s free side. Other edges (occlusion) are ignored."""
    vi, ti, ni, _ = _frame(seg_from)
    vj, tj, _, lj = _frame(seg_to)
    s = np.asarray(s, dtype=np.float64)
    d = _heading(ti, ni, theta)
    p = vi + s[..., None] * ti
    den = _cross(tj, d)  # = <n_j, d>: negative when the ray approaches e_j from its free side
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = _cross(p - vj, d) / den
        lam = _cross(p - vj, tj) / den  # travel distance: p + λ d = v_j + μ t_j
    return (den < 0) & (lam > 0) & (mu >= 0) & (mu <= lj)


def slope(seg_from: object, seg_to: object, theta: object) -> np.ndarray:
    """∂μ/∂s = sin θ / sin(θ − γ); negative for every valid hit (it equals −C)."""
    gamma = relative_direction(seg_from, seg_to)
    theta = np.asarray(theta, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sin(theta) / np.sin(theta - gamma)


def interval_image(seg_from: object, seg_to: object, s_range: object,
                   theta_range: object) -> tuple[float, float]:
    """Image of the box ``[s_lo, s_hi] × [θ_lo, θ_hi]`` on ``seg_to`` (the "cone" of §6).

    μ is affine and decreasing in s and increasing in θ for valid hits, so the image is
    ``[μ(s_hi, θ_lo), μ(s_lo, θ_hi)]``; it is computed as the min/max over the four corners,
    which is the same interval whenever the box lies inside a safe interval.
    """
    s_lo, s_hi = (float(x) for x in s_range)
    t_lo, t_hi = (float(x) for x in theta_range)
    if s_lo > s_hi or t_lo > t_hi:
        raise ValueError(f"empty box: s in {s_range!r}, theta in {theta_range!r}")
    corners = transition(seg_from, seg_to, np.array([s_lo, s_lo, s_hi, s_hi]),
                         np.array([t_lo, t_hi, t_lo, t_hi]))
    return float(np.min(corners)), float(np.max(corners))


# -- contraction (Def. 10–12, Lemma 2) ----------------------------------------------------------

def contraction(seg_i: object, seg_j: object, theta: object) -> np.ndarray:
    """Def. 11 in the unified form C = |sin θ / sin(θ − γ)| (§6; docs/choices/visibility.md,
    "Contraction for non-adjacent edges"); parallel facing edges
    give C = 1. Broadcast over θ."""
    return np.abs(slope(seg_i, seg_j, theta))


def contraction_coefficient(theta: object, phi: float, side: str) -> np.ndarray:
    """Def. 11 in the paper's form: ``|sin θ/sin(θ − φ)|`` (left) or ``|sin θ/sin(θ + φ)|`` (right)."""
    theta = np.asarray(theta, dtype=np.float64)
    if side not in ("left", "right"):
        raise ValueError(f"side must be 'left' or 'right', got {side!r}")
    sign = -1.0 if side == "left" else 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(np.sin(theta) / np.sin(theta + sign * phi))


def is_contracting(seg_i: object, seg_j: object, theta: object) -> np.ndarray:
    """Def. 10: the transition at θ is a contraction, C < 1."""
    return contraction(seg_i, seg_j, theta) < 1.0


def lemma2_threshold(phi: float, side: str) -> float:
    """Lemma 2: a right transition contracts iff θ < π/2 − φ/2, a left one iff θ > π/2 + φ/2."""
    if side == "right":
        return math.pi / 2 - phi / 2
    if side == "left":
        return math.pi / 2 + phi / 2
    raise ValueError(f"side must be 'left' or 'right', got {side!r}")


def contracting_range(seg_i: object, seg_j: object) -> tuple[float, float] | None:
    """The open θ-interval of (0, π) on which the ray can meet ``seg_j``'s line from its free
    side *and* C < 1 (Lemma 2 with the unified γ): ``(0, γ/2)`` for a right transition,
    ``(π + γ/2, π)`` for a left one, ``None`` for parallel lines (C = 1 or no hit)."""
    side = transition_side(seg_i, seg_j)
    if side == "parallel":
        return None
    threshold = lemma2_threshold(interior_angle(seg_i, seg_j), side)
    return (0.0, threshold) if side == "right" else (threshold, math.pi)


def composite_contraction(segments: object, thetas: object) -> float:
    """Def. 12: C(F) = Π_k C(θ_k, φ_{e(k), e(k+1)}) for the path ``segments[0] → … → segments[m]``
    with action ``thetas[k]`` at stage k (a scalar θ is used at every stage)."""
    segs = [np.asarray(s, dtype=np.float64) for s in segments]
    if len(segs) < 2:
        raise ValueError("a transition sequence needs at least two segments")
    th = np.broadcast_to(np.asarray(thetas, dtype=np.float64), (len(segs) - 1,))
    return float(np.prod([contraction(a, b, t) for a, b, t in zip(segs[:-1], segs[1:], th,
                                                                   strict=True)]))


@dataclass(frozen=True)
class CompositeCycle:
    """Fixed point of a closed edge sequence (generalises Theorem 1, §6.1).

    Attributes:
        positions: (m,) contact positions μ_k on ``segments[k]`` (distance from its start).
        points: (m, 2) the contacts.
        coefficient: C(F) (Def. 12).
        offset: A in F(μ) = A + (−1)^m C(F) μ (the return map on ``segments[0]``).
        on_segments: every contact lies on its segment (0 ≤ μ_k ≤ ℓ_k); the composition is only
            the robot's motion if, in addition, every arc is safe (no occlusion).
        stable: ``on_segments`` and C(F) < 1 (Banach: unique attracting limit cycle).
    """

    positions: np.ndarray
    points: np.ndarray
    coefficient: float
    offset: float
    on_segments: bool

    @property
    def stable(self) -> bool:
        return self.on_segments and self.coefficient < 1.0


def composite_fixed_point(segments: object, thetas: object) -> CompositeCycle:
    """Fixed point of the cycle ``segments[0] → segments[1] → … → segments[m−1] → segments[0]``
    with action ``thetas[k]`` leaving ``segments[k]`` (scalar: the same θ at every stage).

    Step k is μ_{k+1} = a_k − C_k μ_k; the composition is F(μ) = A + (−1)^m C(F) μ and the fixed
    point μ* = A / (1 − (−1)^m C(F)). Raises if the return map is the identity's slope (+1).
    """
    segs = [np.asarray(s, dtype=np.float64) for s in segments]
    m = len(segs)
    if m < 2:
        raise ValueError("a cycle needs at least two segments")
    th = np.broadcast_to(np.asarray(thetas, dtype=np.float64), (m,))
    a = np.empty(m)
    b = np.empty(m)
    for k in range(m):
        a[k] = float(transition(segs[k], segs[(k + 1) % m], 0.0, th[k]))
        b[k] = float(slope(segs[k], segs[(k + 1) % m], th[k]))
    offset, gain = 0.0, 1.0
    for k in range(m):
        offset, gain = a[k] + b[k] * offset, b[k] * gain
    if not np.isfinite(offset) or abs(1.0 - gain) <= 1e-15:
        raise ValueError("the return map has slope +1 (or a transition is parallel to its "
                         "heading): no unique fixed point")
    positions = np.empty(m)
    positions[0] = offset / (1.0 - gain)
    for k in range(m - 1):
        positions[k + 1] = a[k] + b[k] * positions[k]
    frames = [_frame(s) for s in segs]
    points = np.array([v + mu * t for (v, t, _, _), mu in zip(frames, positions, strict=True)])
    lengths = np.array([f[3] for f in frames])
    tol = 1e-9 * lengths
    on = bool(np.all((positions >= -tol) & (positions <= lengths + tol)))
    return CompositeCycle(positions, points, float(abs(gain)), float(offset), on)


# -- the fixed rule in convex polygons (Lemma 3, Theorem 1, Cor. 3–4) ---------------------------

def _convex_ring(world: World) -> np.ndarray:
    if world.holes:
        raise ValueError(f"world {world.name!r} has holes; Theorem 1 needs a convex polygon")
    ring = np.asarray(world.outer, dtype=np.float64)
    if np.any(world.reflex[: len(ring)]):
        raise ValueError(f"world {world.name!r} is not convex")
    return ring


def _interior_angles(world: World) -> np.ndarray:
    """Interior angle at every outer vertex v_i (between e_{i−1} and e_i)."""
    n = len(world.outer)
    t_out = world.tangents[:n]
    t_in = np.roll(t_out, 1, axis=0)
    turn = np.arctan2(_cross(t_in, t_out), np.sum(t_in * t_out, axis=1))
    return np.pi - turn


class Lemma3Bound(NamedTuple):
    """Lemma 3: θ ∈ (0, bound) gives a counter-clockwise period-n limit cycle from any start.

    ``visibility`` = min_i ∠v_{i+2} v_i v_{i+1} (e_i always hits e_{i+1}); ``contraction`` =
    min_i (π/2 − φ_i/2) (every step contracts); ``bound`` is their minimum. Clockwise orbits:
    θ ∈ (π − bound, π).
    """

    bound: float
    visibility: float
    contraction: float


def lemma3_bound(world: World) -> Lemma3Bound:
    """Lemma 3's bound for a convex polygon (outer ring counter-clockwise, as `World` stores it)."""
    ring = _convex_ring(world)
    to1 = np.roll(ring, -1, axis=0) - ring
    to2 = np.roll(ring, -2, axis=0) - ring
    angle = np.arctan2(np.abs(_cross(to1, to2)), np.sum(to1 * to2, axis=1))
    vis = float(np.min(angle))
    con = float(np.min(np.pi / 2 - _interior_angles(world) / 2))
    return Lemma3Bound(min(vis, con), vis, con)


@dataclass(frozen=True)
class FixedRuleCycle:
    """Theorem 1: the period-n limit cycle of the fixed rule b = θ in a convex polygon.

    Attributes:
        theta: the action.
        d_fp: fixed point on e_0 as a distance from v_0.
        positions: (n,) contact on every e_k, distance from v_k (forward-projected from d_fp).
        points: (n, 2) the contacts.
        coefficients: (n,) C_k = sin θ / sin(θ + φ_{k,k+1}) (φ at v_{k+1}).
        product: Π C_k = C(F) of one lap.
        valid: every C_k > 0 and every contact lies on its edge (then, the polygon being
            convex, each ray really hits the next edge and the cycle exists).
    """

    theta: float
    d_fp: float
    positions: np.ndarray
    points: np.ndarray
    coefficients: np.ndarray
    product: float
    valid: bool

    @property
    def stable(self) -> bool:
        return self.valid and self.product < 1.0


def fixed_rule_cycle(world: World, theta: float) -> FixedRuleCycle:
    """Theorem 1 for a convex polygon and the counter-clockwise fixed rule (θ ∈ (0, π/2]).

    ``d_FP = Σ_j (−1)^{n−j−1} ℓ_j Π_{k=j}^{n−1} C_k / (1 − (−1)^n Π_k C_k)``, linear in n. The
    other contacts follow by d_{k+1} = C_k (ℓ_k − d_k). Lemma 3's bound guarantees the cycle is
    reached from every start; outside it check ``valid``/``stable``. Clockwise cycles: mirror the
    polygon.
    """
    theta = float(theta)
    if not 0.0 < theta < math.pi:
        raise ValueError(f"theta must be in (0, pi), got {theta}")
    ring = _convex_ring(world)
    n = len(ring)
    lengths = np.asarray(world.lengths[:n], dtype=np.float64)
    phi_next = np.roll(_interior_angles(world), -1)  # φ_{k,k+1}: the angle at v_{k+1}
    coeff = math.sin(theta) / np.sin(theta + phi_next)
    tail = np.cumprod(coeff[::-1])[::-1]  # Π_{k=j}^{n−1} C_k
    signs = (-1.0) ** (n - np.arange(n) - 1)
    product = float(tail[0])
    d_fp = float(np.sum(signs * lengths * tail) / (1.0 - (-1.0) ** n * product))
    positions = np.empty(n)
    positions[0] = d_fp
    for k in range(n - 1):
        positions[k + 1] = coeff[k] * (lengths[k] - positions[k])
    points = world.edge_start[:n] + positions[:, None] * world.tangents[:n]
    tol = 1e-9 * lengths
    valid = bool(np.all(coeff > 0) and np.all((positions >= -tol) & (positions <= lengths + tol)))
    return FixedRuleCycle(theta, d_fp, positions, points, coeff, product, valid)


def regular_ngon_fixed_point(n: int, side: float, theta: float) -> float:
    """Theorem 1, regular n-gon with side ℓ: d* = ℓC/(1 + C), C = sin θ / sin(θ + (n−2)π/n),
    for θ < π/n."""
    c = math.sin(theta) / math.sin(theta + (n - 2) * math.pi / n)
    return side * c / (1.0 + c)


def rectangle_fixed_point(width: float, height: float, theta: float) -> float:
    """Theorem 1, rectangle with bottom W and side H: d = (Hc − Wc²)/(1 − c²), c = tan θ
    (distance from the bottom-left corner along the bottom edge)."""
    c = math.tan(theta)
    return (height * c - width * c * c) / (1.0 - c * c)


def cor3_bound(coefficient: float, length: float, k: int) -> float:
    """Cor. 3: |F^k(x_0) − x_FP| ≤ C^k ℓ_i (also a bound on the diameter of the position set)."""
    return float(coefficient) ** int(k) * float(length)


def iterations_to(eps: float, coefficient: float, length: float) -> int:
    """Cor. 4: laps after which the set of possible positions is smaller than ε,
    ``⌈log(ε/(2ℓ)) / log C⌉``. Conservative (docs/choices/visibility.md, "Corollary 4 is conservative"): the
    set diameter is only ≤ C^k ℓ, so fewer laps often suffice (the WAFR version used ε/ℓ). Returns 0
    if ε ≥ 2ℓ already."""
    if not 0.0 < coefficient < 1.0:
        raise ValueError(f"Cor. 4 needs a contraction, 0 < C < 1; got C = {coefficient}")
    if eps <= 0 or length <= 0:
        raise ValueError(f"eps and length must be > 0, got eps={eps}, length={length}")
    ratio = eps / (2.0 * length)
    if ratio >= 1.0:
        return 0
    return math.ceil(math.log(ratio) / math.log(coefficient))


# -- simulation (ground truth for the analytic results) ----------------------------------------

@dataclass(frozen=True)
class FixedRuleTrace:
    """Contacts of m point robots under the fixed rule; index 0 is the start.

    Attributes:
        edges: (m, k+1) edge index of each contact.
        positions: (m, k+1) distance of each contact from the start vertex of its edge.
        points: (m, k+1, 2) the contacts.
    """

    edges: np.ndarray
    positions: np.ndarray
    points: np.ndarray


def sample_boundary(world: World, rng: np.random.Generator, m: int,
                    margin: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """m random boundary points as (edges, positions): edges ∝ length, positions uniform on the
    middle ``1 − 2·margin`` of the edge (away from the vertices)."""
    p = world.lengths / world.lengths.sum()
    edges = rng.choice(world.n_edges, size=m, p=p)
    frac = rng.uniform(margin, 1.0 - margin, size=m)
    return edges, frac * world.lengths[edges]


def simulate_fixed_rule(world: World, theta: object, start: tuple[object, object],
                        n_bounces: int) -> FixedRuleTrace:
    """Run the exact fixed rule (u = θ from the boundary tangent, point robot) for ``n_bounces``
    contacts with `World.first_hit`.

    Args:
        world: the workspace (any polygon, holes allowed).
        theta: the action, scalar or one per robot.
        start: ``(edges, positions)``: start edge index and distance from its start vertex,
            scalars or arrays of length m.
        n_bounces: number of stages.
    """
    edges0, pos0 = start
    edge = np.atleast_1d(np.asarray(edges0, dtype=np.int64)).copy()
    pos = np.atleast_1d(np.asarray(pos0, dtype=np.float64)).copy()
    edge, pos = np.broadcast_arrays(edge, pos)
    edge, pos = edge.copy(), pos.copy()
    m = len(edge)
    th = np.broadcast_to(np.asarray(theta, dtype=np.float64), (m,))
    if np.any((th <= 0) | (th >= np.pi)):
        raise ValueError("theta must lie in (0, pi)")
    if np.any((edge < 0) | (edge >= world.n_edges)):
        raise ValueError(f"start edges must be in [0, {world.n_edges})")
    cos_t, sin_t = np.cos(th)[:, None], np.sin(th)[:, None]
    edges = np.empty((m, n_bounces + 1), dtype=np.int64)
    positions = np.empty((m, n_bounces + 1))
    points = np.empty((m, n_bounces + 1, 2))
    pts = world.edge_start[edge] + pos[:, None] * world.tangents[edge]
    edges[:, 0], positions[:, 0], points[:, 0] = edge, pos, pts
    for k in range(1, n_bounces + 1):
        direction = cos_t * world.tangents[edge] + sin_t * world.normals[edge]
        hits = world.first_hit(pts, direction)
        if np.any(hits.edge < 0):
            raise RuntimeError(f"a robot left the world at stage {k} (start outside P?)")
        pts = pts + hits.distance[:, None] * direction
        edge = hits.edge
        pos = np.clip(np.sum((pts - world.edge_start[edge]) * world.tangents[edge], axis=1),
                      0.0, world.lengths[edge])
        edges[:, k], positions[:, k], points[:, k] = edge, pos, pts
    return FixedRuleTrace(edges, positions, points)
