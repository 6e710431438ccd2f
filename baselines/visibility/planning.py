"""Safe planning and patrolling over G_safe (Nilles et al. 2021, §7.1–7.2).

* `constant_strategy`: Alg. 2 SafeConstantFixedNavigate / SearchConstantFixedStrats. A BFS over
  states (set of current segments, θ̃) starting from θ̃ = (0, π); each arc intersects θ̃ with its
  safe interval and empty intersections are pruned (§7.1.1). With a start *set* of several segments
  every segment follows one arc at each stage with the same θ̃ (docs/choices/visibility.md, "Start and goal
  sets split the partition"). Tie-break (docs/choices/visibility.md, "Ties among shortest safe plans"):
  ``order="shortest"`` (default) takes the widest θ̃ among the shortest feasible paths, which is
  the paper's published answer; ``order="widest"`` takes the widest θ̃ among all paths of at most
  ``max_arcs`` arcs, then the fewest arcs.
* `fewest_bounce_plan`: unweighted shortest path in G_safe, ties broken lexicographically
  (the paper's answer) or by the widest minimum interval (``tie="widest"``); every stage uses its own arc's interval (no intersection across stages).
* `bottleneck_plan`: among paths of at most ``max_arcs`` arcs, the largest minimum interval width
  (then the fewest arcs).
* `split_at`: refine P' at the end points of S and G (docs/choices/visibility.md, "Start and goal sets split
  the partition").
* `patrol`: Def. 15 (§7.2) searched as in docs/choices/visibility.md, "Patrolling search" (colour = original
  edge).
* `PlanPolicy`: executes a `VisibilityPlan` in `BounceEnv` (fixed rule, continuous actions).
* `monte_carlo`: success rate of a plan under exact ray casting (`World.first_hit`).

Intervals are stored closed but their end rays hit vertices, so every sampler draws strictly
inside them (docs/choices/visibility.md, "Sample strictly inside a safe interval").
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import networkx as nx
import numpy as np

from baselines.policy import Policy, episode_rng
from baselines.visibility.dynamics import CompositeCycle, composite_fixed_point, contraction
from baselines.visibility.partition import Partition, assemble_partition
from bounce_gym.errors import ConfigError

__all__ = [
    "PatrolPlan",
    "PlanPolicy",
    "VisibilityPlan",
    "bottleneck_plan",
    "constant_strategy",
    "fewest_bounce_plan",
    "monte_carlo",
    "patrol",
    "split_at",
]

#: Minimum width (rad) of a non-empty θ̃ (below it an intersection counts as empty).
EMPTY_TOL = 1e-9


def _as_set(nodes: int | Iterable[int]) -> frozenset[int]:
    if isinstance(nodes, int | np.integer):
        return frozenset((int(nodes),))
    out = frozenset(int(k) for k in nodes)
    if not out:
        raise ValueError("a start or goal set needs at least one segment")
    return out


@dataclass(frozen=True)
class VisibilityPlan:
    """A staged plan over G_safe.

    Attributes:
        stages: the set of possible current segments before each stage and after the last one
            (``len(stages) = n_arcs + 1``); singletons for single-segment plans.
        intervals: (lo, hi) per stage: sample θ strictly inside it at that stage.
        constant: the constant interval θ̃ (constant strategies) or None.
        width: width of ``constant`` for constant strategies, else the minimum stage width.
        kind: ``"constant"``, ``"fewest"`` or ``"bottleneck"``.
        goal: the goal segments.
    """

    stages: tuple[tuple[int, ...], ...]
    intervals: tuple[tuple[float, float], ...]
    constant: tuple[float, float] | None
    width: float
    kind: str
    goal: tuple[int, ...] = ()

    @property
    def n_arcs(self) -> int:
        return len(self.intervals)

    @property
    def path(self) -> list[int]:
        """The segment path (single-segment stages only)."""
        if any(len(s) != 1 for s in self.stages):
            raise ValueError("this plan runs over sets of segments; use `stages`")
        return [s[0] for s in self.stages]

    @property
    def start(self) -> tuple[int, ...]:
        return self.stages[0]


# -- constant strategies (Alg. 2) ---------------------------------------------------------------

def _arc(g: nx.DiGraph, u: int, v: int) -> tuple[float, float]:
    d = g.edges[u, v]
    return float(d["lo"]), float(d["hi"])


def constant_strategy(g: nx.DiGraph, start: int | Iterable[int], goal: int | Iterable[int],
                      max_arcs: int, order: str = "shortest") -> VisibilityPlan | None:
    """SearchConstantFixedStrats: the widest constant θ̃ taking every segment of ``start`` to
    ``goal`` in at most ``max_arcs`` arcs, or None.

    BFS over states (set of current segments, θ̃) with θ̃ = (0, π) initially; every segment of the
    current set takes one out-arc and θ̃ is intersected with its interval; empty (or narrower
    than `EMPTY_TOL`) intersections are pruned, as are states whose θ̃ is contained in another
    state's with the same set at the same depth. The goal test is "the whole set lies in the
    goal". ``order`` is the tie-break, see the module docstring.
    """
    if order not in ("shortest", "widest"):
        raise ValueError(f"order must be 'shortest' or 'widest', got {order!r}")
    s0, goal_set = _as_set(start), _as_set(goal)
    for k in s0 | goal_set:
        if k not in g:
            raise ValueError(f"segment {k} is not a node of G_safe")
    # frontier: set -> list of (lo, hi, history); history = tuple of sets visited
    frontier: dict[frozenset, list[tuple[float, float, tuple]]] = {s0: [(0.0, math.pi, (s0,))]}
    best: tuple[float, int, float, float, tuple] | None = None
    if s0 <= goal_set:
        best = (math.pi, 0, 0.0, math.pi, (s0,))
    for depth in range(1, max_arcs + 1):
        if best is not None and order == "shortest":
            break
        nxt: dict[frozenset, list[tuple[float, float, tuple]]] = {}
        for cur, states in frontier.items():
            # per current segment, its out-arcs; the product gives the successor sets
            choices = [[(v, *_arc(g, u, v)) for v in g.successors(u)] for u in sorted(cur)]
            for lo0, hi0, hist in states:
                _expand(choices, 0, lo0, hi0, frozenset(), hist, nxt)
        for states in nxt.values():
            states.sort(key=lambda x: x[0] - x[1])  # widest first
            kept: list[tuple[float, float, tuple]] = []
            for st in states:  # drop states whose interval is inside a kept one
                if not any(k[0] <= st[0] and st[1] <= k[1] for k in kept):
                    kept.append(st)
            states[:] = kept
        for cur, states in nxt.items():
            if cur <= goal_set:
                lo, hi, hist = states[0]
                cand = (hi - lo, -depth, lo, hi, hist)
                if best is None or cand[:2] > best[:2]:
                    best = cand
        frontier = nxt
        if not frontier:
            break
    if best is None:
        return None
    width, _, lo, hi, hist = best
    n = len(hist) - 1
    return VisibilityPlan(tuple(tuple(sorted(s)) for s in hist), ((lo, hi),) * n, (lo, hi),
                          float(width), "constant", tuple(sorted(goal_set)))


def _expand(choices, i, lo, hi, acc, hist, out) -> None:
    if i == len(choices):
        out.setdefault(acc, []).append((lo, hi, (*hist, acc)))
        return
    for v, a, b in choices[i]:
        nlo, nhi = max(lo, a), min(hi, b)
        if nhi - nlo > EMPTY_TOL:
            _expand(choices, i + 1, nlo, nhi, acc | {v}, hist, out)


# -- per-stage plans ----------------------------------------------------------------------------

def _plan_from_path(g: nx.DiGraph, path: Sequence[int], kind: str,
                    goal: frozenset[int]) -> VisibilityPlan:
    intervals = tuple(_arc(g, u, v) for u, v in zip(path[:-1], path[1:], strict=True))
    width = min((hi - lo for lo, hi in intervals), default=math.pi)
    return VisibilityPlan(tuple((int(k),) for k in path), intervals, None, float(width), kind,
                          tuple(sorted(goal)))


def fewest_bounce_plan(g: nx.DiGraph, start: int, goal: int | Iterable[int],
                       tie: str = "first") -> VisibilityPlan | None:
    """Unweighted shortest path from ``start`` to any goal segment in G_safe (§7.1). None if the
    goal is unreachable.

    ``tie`` chooses among the shortest paths: ``"first"`` (default) the lexicographically
    smallest node sequence (BFS with ascending successors), which reproduces the paper's
    published fewest-transition plan (two_rooms e0→e16 = 0→17→6→16, §7.1.2); ``"widest"`` the path
    with the widest minimum interval (on two_rooms that is the bottleneck plan 0→18→9→16).
    """
    if tie not in ("first", "widest"):
        raise ValueError(f"tie must be 'first' or 'widest', got {tie!r}")
    goal_set = _as_set(goal)
    start = int(start)
    if start in goal_set:
        return _plan_from_path(g, [start], "fewest", goal_set)
    h = g.copy()
    sink = -1
    h.add_edges_from((k, sink) for k in goal_set if k in h)
    try:
        paths = [p[:-1] for p in nx.all_shortest_paths(h, start, sink)]
    except nx.NetworkXNoPath:
        return None
    if tie == "first":
        best = min(paths)
    else:
        best = max(sorted(paths), key=lambda p: min(
            g.edges[u, v]["width"] for u, v in zip(p[:-1], p[1:], strict=True)))
    return _plan_from_path(g, best, "fewest", goal_set)


def bottleneck_plan(g: nx.DiGraph, start: int, goal: int | Iterable[int],
                    max_arcs: int) -> VisibilityPlan | None:
    """Among paths of at most ``max_arcs`` arcs from ``start`` to the goal, the one with the
    largest minimum interval width (ties: fewest arcs). Layered max–min DP over walks; a walk can
    be cut to a simple path without lowering its bottleneck, and the DP keeps the first
    (shortest) walk reaching each value, so the result is a path."""
    goal_set = _as_set(goal)
    start = int(start)
    if start in goal_set:
        return _plan_from_path(g, [start], "bottleneck", goal_set)
    layer = {start: (math.inf, (start,))}
    best: tuple[float, int, tuple] | None = None
    for depth in range(1, max_arcs + 1):
        nxt: dict[int, tuple[float, tuple]] = {}
        for u, (b, path) in layer.items():
            for v in g.successors(u):
                if v in path:
                    continue
                w = min(b, g.edges[u, v]["width"])
                if v not in nxt or w > nxt[v][0]:
                    nxt[v] = (w, (*path, v))
        for v, (w, path) in nxt.items():
            if v in goal_set and (best is None or w > best[0]):
                best = (w, depth, path)
        layer = nxt
    if best is None:
        return None
    return _plan_from_path(g, best[2], "bottleneck", goal_set)


# -- refinement of P' (docs/choices/visibility.md, "Start and goal sets split the partition") ----------

def split_at(part: Partition, points: object) -> Partition:
    """P' refined at ``points`` (each on ∂P, e.g. the end points of S and G;
    docs/choices/visibility.md, "Start and goal sets split the partition").

    Sub-segments of an entirely visible pair stay entirely visible, so Prop. 2 still applies to
    the refined partition. Points within the partition's snapping tolerance of an existing vertex
    are ignored. Segment ids change: use ``locate`` on the result.
    """
    world = part.world
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    snap = part.tol
    cuts: list[list[float]] = [[] for _ in range(world.n_edges)]
    flags: list[list[tuple[bool, bool]]] = [[] for _ in range(world.n_edges)]
    for k in range(part.n):
        e = int(part.edge[k])
        cuts[e].append(float(np.dot(part.start[k] - world.edge_start[e], world.tangents[e])))
        flags[e].append((bool(part.inserted[k]), bool(part.reflex[k])))
    for p in pts:
        rel = p - world.edge_start
        s = np.einsum("ij,ij->i", rel, world.tangents)
        off = np.abs(rel[:, 0] * world.tangents[:, 1] - rel[:, 1] * world.tangents[:, 0])
        ok = (s >= -snap) & (s <= world.lengths + snap)
        if not ok.any():
            raise ValueError(f"point {p.tolist()} is not on the boundary")
        e = int(np.flatnonzero(ok)[np.argmin(off[ok])])
        if off[e] > 1e3 * snap:
            raise ValueError(f"point {p.tolist()} is not on the boundary")
        s_e = float(s[e])
        if s_e <= snap or s_e >= world.lengths[e] - snap:
            continue
        if min(abs(s_e - c) for c in cuts[e]) <= snap:
            continue
        cuts[e].append(s_e)
        flags[e].append((True, False))
    start, ring, edge, inserted, reflex = [], [], [], [], []
    for e in range(world.n_edges):
        order = np.argsort(cuts[e])
        for i in order:
            start.append(world.edge_start[e] + cuts[e][i] * world.tangents[e])
            ring.append(int(world.edge_ring[e]))
            edge.append(e)
            inserted.append(flags[e][i][0])
            reflex.append(flags[e][i][1])
    return assemble_partition(world, start, ring, edge, inserted, reflex, part.closed, part.tol)


# -- patrolling (Def. 15) -----------------------------------------------------------------------

@dataclass(frozen=True)
class PatrolPlan:
    """A patrolling cycle of G_safe (Def. 15).

    Attributes:
        cycle: segment ids ``z_0 → z_1 → … → z_{m−1} → z_0``.
        intervals: safe interval of each cycle arc.
        thetas: the chosen action per arc (strictly inside its interval).
        coefficient: C(F) at ``thetas``.
        c_min, c_max: Π min C and Π max C over the intervals (end-point evaluations).
        robust: ``c_max < 1`` (every θ in the intervals contracts).
        colours: the collapsed original-edge colours of the cycle.
        fixed_point: the limit cycle (`composite_fixed_point`).
        approach: a fewest-bounce plan from the start segment to a cycle node (None if no start).
    """

    cycle: tuple[int, ...]
    intervals: tuple[tuple[float, float], ...]
    thetas: tuple[float, ...]
    coefficient: float
    c_min: float
    c_max: float
    robust: bool
    colours: tuple[int, ...]
    fixed_point: CompositeCycle
    approach: VisibilityPlan | None = None

    @property
    def stable(self) -> bool:
        return self.fixed_point.stable


def _collapse(colours: Sequence[int]) -> list[int]:
    out: list[int] = []
    for c in colours:
        if not out or out[-1] != c:
            out.append(c)
    while len(out) > 1 and out[0] == out[-1]:
        out.pop()
    return out


def _contains_cyclically(cols: list[int], seq: Sequence[int], strict: bool) -> bool:
    n = len(cols)
    for r in range(n):
        rot = cols[r:] + cols[:r]
        if strict:
            if rot == list(seq):
                return True
            continue
        it = iter(rot)
        if all(any(c == s for c in it) for s in seq):
            return True
    return False


def patrol(g: nx.DiGraph, part: Partition, edge_sequence: Sequence[int], max_len: int,
           start: int | None = None, theta: float | None = None, strict: bool = False,
           margin: float = 0.05, select: str = "coefficient") -> PatrolPlan | None:
    """Def. 15: a contracting cycle of G_safe visiting the original edges ``edge_sequence`` in
    cyclic order (docs/choices/visibility.md, "Patrolling search").

    Args:
        g: G_safe.
        part: its partition (node colour = ``part.edge``).
        edge_sequence: original world edge ids E = (e_1 … e_k).
        max_len: longest cycle (arcs) searched (`networkx.simple_cycles` with ``length_bound``).
        start: if given, the approach is a fewest-bounce plan from this segment to the cycle.
        theta: if given, one fixed action for every stage; only cycles whose every interval
            strictly contains it qualify, and C is evaluated at θ (a fixed-rule limit cycle).
        strict: the collapsed colours must equal E up to rotation (else E is a cyclic
            subsequence).
        margin: chosen angles lie this fraction of the width inside the best end point.
        select: ``"coefficient"`` (smallest C(F)) or ``"width"`` (largest minimum width) among
            the candidates; robust candidates (Π max C < 1) come first.

    Returns:
        The best candidate whose fixed point lies on its segments, or None.
    """
    seq = [int(e) for e in edge_sequence]
    cands = []
    for cyc in nx.simple_cycles(g, length_bound=max_len):
        if len(cyc) < 2:
            continue
        cols = _collapse([int(part.edge[k]) for k in cyc])
        if not _contains_cyclically(cols, seq, strict):
            continue
        arcs = list(zip(cyc, cyc[1:] + cyc[:1], strict=True))
        ivs = [_arc(g, u, v) for u, v in arcs]
        segs = [part.segment(k) for k in cyc]
        c_lo, c_hi, thetas = [], [], []
        for (u, v), (lo, hi) in zip(arcs, ivs, strict=True):
            su, sv = part.segment(u), part.segment(v)
            ends = contraction(su, sv, np.array([lo, hi]))
            c_lo.append(float(np.min(ends)))
            c_hi.append(float(np.max(ends)))
            if theta is None:
                w = hi - lo
                thetas.append(lo + margin * w if ends[0] <= ends[1] else hi - margin * w)
        if theta is not None:
            if not all(lo < theta < hi for lo, hi in ivs):
                continue
            thetas = [float(theta)] * len(cyc)
            cvals = [float(contraction(part.segment(u), part.segment(v), theta)) for u, v in arcs]
            c_min = c_max = float(np.prod(cvals))
        else:
            c_min, c_max = float(np.prod(c_lo)), float(np.prod(c_hi))
        if c_min >= 1.0:
            continue
        try:
            fp = composite_fixed_point(segs, thetas)
        except ValueError:
            continue
        if not fp.on_segments or fp.coefficient >= 1.0:
            continue
        width = min(hi - lo for lo, hi in ivs)
        key = (not c_max < 1.0, fp.coefficient if select == "coefficient" else -width, len(cyc))
        cands.append((key, tuple(int(k) for k in cyc), tuple(ivs), tuple(thetas), fp, c_min,
                      c_max, tuple(cols)))
    if not cands:
        return None
    cands.sort(key=lambda c: c[0])
    _, cyc, ivs, thetas, fp, c_min, c_max, cols = cands[0]
    approach = fewest_bounce_plan(g, start, set(cyc)) if start is not None else None
    return PatrolPlan(cyc, ivs, thetas, fp.coefficient, c_min, c_max, c_max < 1.0, cols, fp,
                      approach)


# -- execution ----------------------------------------------------------------------------------

def _inside(rng: np.random.Generator, lo, hi, margin: float, size=None):
    """Uniform samples strictly inside (lo, hi), ``margin`` of the width away from each end."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    w = hi - lo
    a, b = lo + margin * w, hi - margin * w
    x = rng.uniform(a, b, size=size)
    return np.clip(x, np.nextafter(lo, hi), np.nextafter(hi, lo))


class _ThetaSamplingPolicy(Policy):
    """What the two visibility policies share: they run in `BounceEnv` with Nilles et al.'s
    fixed rule and continuous actions, and draw θ strictly inside safe intervals from a random
    stream that restarts every episode (`baselines.policy.episode_rng`)."""

    seed: int | None
    rng: np.random.Generator
    range: tuple[float, float]

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_rng(self.seed, seed)
        return None

    def _bind(self, env) -> None:
        """Check the env runs the fixed rule with continuous actions; take its action range."""
        opts = env.unwrapped.options
        if opts.bounce_rule != "fixed" or opts.action_type != "continuous":
            raise ConfigError(f"{type(self).__name__} needs BounceEnv(bounce_rule='fixed', "
                              f"action_type='continuous'), got {opts.bounce_rule!r}, "
                              f"{opts.action_type!r}")
        self.range = tuple(float(x) for x in opts.angle_range[0])


@dataclass
class PlanPolicy(_ThetaSamplingPolicy):
    """Run a `VisibilityPlan` in `BounceEnv` (``bounce_rule="fixed"``, continuous actions).

    At each contact the robot's P' segment is ``part.locate(info["contact_edge"],
    info["position"])``; the stage is the position of that segment on the plan (the next one
    expected, else any later stage). θ is drawn uniformly strictly inside the stage's interval
    intersected with the env's ``angle_range`` and mapped to the action a ∈ [−1, 1]. Off the plan
    the policy replans with `fewest_bounce_plan` when ``graph`` is given (``replans`` counts it),
    else it stops following (``off_plan``) and acts in the middle of the range.
    ``reached_goal`` turns True when a contact lies on a goal segment.
    """

    plan: VisibilityPlan
    part: Partition
    seed: int | None = None
    margin: float = 0.02
    graph: nx.DiGraph | None = None
    name: str = "visibility plan"
    rng: np.random.Generator = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)
        self._current = self.plan
        self.stage = 0
        self.reached_goal = False
        self.off_plan = False
        self.replans = 0
        self.range = (0.0, math.pi)

    def reset(self, env) -> None:
        self._bind(env)
        self._check(self.plan)
        self._current = self.plan
        self.stage, self.reached_goal, self.off_plan, self.replans = 0, False, False, 0

    def _check(self, plan: VisibilityPlan) -> None:
        lo_r, hi_r = self.range
        for k, (lo, hi) in enumerate(plan.intervals):
            if min(hi, hi_r) - max(lo, lo_r) <= EMPTY_TOL:
                raise ValueError(
                    f"stage {k}: safe interval ({lo:.4f}, {hi:.4f}) rad lies outside the env's "
                    f"angle_range ({lo_r:.4f}, {hi_r:.4f}) rad ({math.degrees(lo_r):g}°, "
                    f"{math.degrees(hi_r):g}°)")

    def segment(self, info: dict) -> int:
        return int(self.part.locate([int(info["contact_edge"])], [info["position"]])[0])

    def act(self, observation, info):
        seg = self.segment(info)
        plan = self._current
        if seg in plan.goal:
            self.reached_goal = True
        stages = [s for s in range(self.stage, plan.n_arcs) if seg in plan.stages[s]]
        if stages:
            self.stage = stages[0]
        elif not self.reached_goal:
            new = fewest_bounce_plan(self.graph, seg, plan.goal) if self.graph is not None else None
            if new is None or new.n_arcs == 0:
                self.off_plan = True
                return self._action(0.5 * (self.range[0] + self.range[1]))
            self._check(new)
            self._current, self.stage, plan = new, 0, new
            self.replans += 1
        else:
            return self._action(0.5 * (self.range[0] + self.range[1]))
        lo, hi = plan.intervals[self.stage]
        lo, hi = max(lo, self.range[0]), min(hi, self.range[1])
        theta = float(_inside(self.rng, lo, hi, self.margin))
        self.stage += 1
        return self._action(theta)

    def _action(self, theta: float) -> np.ndarray:
        lo, hi = self.range
        a = 2.0 * (theta - lo) / (hi - lo) - 1.0
        return np.array([min(max(a, -1.0), 1.0)], dtype=np.float32)


# -- Monte-Carlo validation ---------------------------------------------------------------------

def monte_carlo(world, part: Partition, plan: VisibilityPlan, n: int = 1000, seed: int | None = 0,
                margin: float = 0.0, return_counts: bool = False):
    """Success rate of ``plan`` from uniformly random start points on its start segment(s) with
    θ ~ U(stage interval) (strictly inside) at every stage, by exact ray casting
    (`World.first_hit`, fixed rule: heading θ from the contact edge's tangent).

    A run succeeds when every contact lies on one of the stage's segments and the last one on a
    goal segment; a ray that leaves the world counts as a failure. ``return_counts``: return
    ``(rate, successes)``.
    """
    rng = np.random.default_rng(seed)
    starts = np.asarray(plan.stages[0])
    p = part.length[starts] / part.length[starts].sum()
    seg = starts[rng.choice(len(starts), size=n, p=p)]
    frac = rng.uniform(0.0, 1.0, size=n)
    frac = np.clip(frac, 1e-12, 1 - 1e-12)
    pts = part.start[seg] + (frac * part.length[seg])[:, None] * part.tangent[seg]
    wedge = part.edge[seg].copy()
    ok = np.ones(n, dtype=bool)
    for k, (lo, hi) in enumerate(plan.intervals):
        theta = _inside(rng, lo, hi, margin, size=n)
        d = (np.cos(theta)[:, None] * part.world.tangents[wedge]
             + np.sin(theta)[:, None] * part.world.normals[wedge])
        hits = part.world.first_hit(pts, d)
        ok &= hits.edge >= 0
        pts = pts + np.where(ok, hits.distance, 0.0)[:, None] * d
        wedge = np.where(ok, hits.edge, 0)
        seg = part.locate(wedge, pts)
        allowed = np.asarray(plan.stages[k + 1])
        ok &= np.isin(seg, allowed)
    if plan.goal:
        ok &= np.isin(seg, np.asarray(plan.goal))
    rate = float(ok.mean())
    return (rate, int(ok.sum())) if return_counts else rate


@dataclass
class PatrolPolicy(_ThetaSamplingPolicy):
    """Run a `PatrolPlan` in `BounceEnv` (``bounce_rule="fixed"``, continuous actions).

    On a segment of the cycle the robot bounces with that stage's action (``plan.thetas``), so it
    converges to the cycle's fixed point (Theorem 1 / the composite form); elsewhere it follows a
    fewest-bounce plan to the cycle (sampling strictly inside each interval).
    """

    plan: PatrolPlan
    part: Partition
    graph: nx.DiGraph
    seed: int | None = None
    margin: float = 0.02
    name: str = "patrol cycle"
    rng: np.random.Generator = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)
        self.range = (0.0, math.pi)

    def reset(self, env) -> None:
        self._bind(env)
        outside = [t for t in self.plan.thetas if not self.range[0] <= t <= self.range[1]]
        if outside:
            raise ValueError(f"the cycle's actions {outside} rad lie outside the env's "
                             f"angle_range {self.range} rad")

    def act(self, observation, info):
        seg = int(self.part.locate([int(info["contact_edge"])], [info["position"]])[0])
        if seg in self.plan.cycle:
            theta = self.plan.thetas[self.plan.cycle.index(seg)]
        else:
            approach = fewest_bounce_plan(self.graph, seg, set(self.plan.cycle))
            if approach is None or approach.n_arcs == 0:
                theta = 0.5 * (self.range[0] + self.range[1])
            else:
                lo, hi = approach.intervals[0]
                lo, hi = max(lo, self.range[0]), min(hi, self.range[1])
                theta = float(_inside(self.rng, lo, hi, self.margin))
        lo, hi = self.range
        return np.array([min(max(2.0 * (theta - lo) / (hi - lo) - 1.0, -1.0), 1.0)],
                        dtype=np.float32)
