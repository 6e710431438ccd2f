"""Navigation with bounce policies: the roadmap, minimum plans, all plans, and plan execution.

This is Alg. 1 ROADMAP&PLAN and Alg. 2 ALLPLANGENERATION of Alam, Bobadilla & Shell, "Minimalist
robot navigation and coverage using a dynamical system approach" (IEEE IRC 2017; thesis Alg. 3.1 /
3.2), on the deterministic cell model `bounce_gym.cells.CellModel` (ε = 0: the robot rotates
reliably by the angles of Φ).

**The roadmap is the layered product graph** (docs/choices/navigation_coverage.md, "The roadmap remembers the current
bounce angle"). The paper (Sec. IV-A)
takes the union of one graph G_i per policy over the same vertex set, which loses which policy is
active, so "the bounce changes the angle" (weight w2) cannot be known. Here a node is a pair
(cell z, active angle i), numbered ``v = i·N + z``:

* forward edge ``(z, i) → (z', i)`` of weight w1 when the step from z is free (observation 0);
* bump edges at a blocked cell: ``(z, i) → (z ⊕ φ_i, i)`` of weight w1 (the angle is kept) and
  ``(z, i) → (z ⊕ φ_k, k)`` of weight w2 for every k ≠ i (the angle changes); ``z ⊕ φ`` is the
  same position with the heading rotated counter-clockwise by φ (a bump rotates in place,
  docs/choices/cell_model.md, "Bumps rotate in place and take one tick");
* the first policy is free: a query starts from all layers ``(x_I, i)`` at distance 0 (one
  Dijkstra with several sources and ``min_only=True``, i.e. a super-source) and ends at the best
  layer of ``x_G``.

A plan's weight is therefore ``w1·(ticks) + (w2 − w1)·(angle changes)``: with w2 larger than w1
times the longest path this is lexicographic (fewest angle changes first, then fewest ticks).
Every edge stores its kind (forward / bump) and its angle, and the observation string ỹ is read
from the edges of the path: ``0`` per forward edge and φ (degrees) per bump edge, never from the
index distance of consecutive cells (the paper's NAVIGATIONPLAN test, which needs orientation-major
numbering and N_pos, not N, as threshold).

**All plans (Alg. 2)** with the line-12 inversion fixed (A9: no path ⇒ L = −1, the diagonal is 0):
one multi-layer single-source Dijkstra per start cell (N calls, not N² pair queries), keeping the
weights ``L`` (N × N) and the end layers (N × N); a plan ``M[i][j]`` is decoded when asked for
from the predecessor tree of start i, so the N² strings are never stored. The diagonal plan is
the empty plan (the paper's M is NIL there); ``plan is None ⇔ L = −1`` holds for every pair.

**Memory of all plans.** ``L`` is float32 when that is exact (sums of w1 and w2 such as the
paper's 1 and 100 are), else float64; the end layers are int8: 5 bytes per pair (about 0.8 GB at
12,480 cells), plus 1 byte per pair once the angle statistics are asked for. Of the predecessor
trees (4·N·|Φ| bytes each) only as many as fit in ``tree_budget`` (default `TREE_BUDGET`) are
kept, the most recently used ones; a tree that is not kept is searched again when a plan from
its start is decoded. The angle statistics are computed in blocks of start cells
(`BLOCK_BYTES` of work arrays). Small maps (N·|Φ|·N·4 bytes within the budget: 26 MB for
lab_complex) keep every tree and never search twice.

**Policies.** `PlanExecutor` replays a plan in a `bounce_gym.envs.BounceEnv` with
``step_mode="bounce"`` (one step = one bump tick with the chosen angle, then driving to the next
contact), using discrete actions (indices into the env's Φ); with ``backend="cell"`` the env steps
the cell model exactly and the plan reaches its goal. `NavigationPlanner` reads the episode's
start and goal from the env's navigation task, plans on the cell model, and executes.

Cells are 0-based (``z = k·N_pos + p``); the papers' ids are ``z + 1``. Angles of Φ are given in
**degrees** (as in the papers' plans and in the env's ``angles``); they must be whole orientation
bins of the model and distinct modulo 360°.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from bounce_gym.cells import CellModel
from bounce_gym.cells.outcomes import GOAL_SLACK
from bounce_gym.errors import ConfigError

__all__ = ["FORWARD", "BUMP", "Plan", "Roadmap", "AllPlans", "goal_cells"]

#: edge kinds of the roadmap
FORWARD, BUMP = 0, 1
_NO_PRED = -9999  # scipy's predecessor value for "no predecessor"
#: Default bytes of predecessor trees `Roadmap.all_pairs` keeps.
TREE_BUDGET = 64 * 2**20
#: Bytes of work arrays per block of start cells in `AllPlans.angle_masks`.
BLOCK_BYTES = 32 * 2**20


# -- plans ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Plan:
    """A minimum navigation plan (the observation string ỹ of the paper) and its path.

    Attributes:
        start, goal: cell numbers (0-based) of the query; ``goal`` is the cell the path ends in.
        cells: the cell path, ``cells[0] == start``, ``cells[-1] == goal``; one more than symbols.
        layers: the active angle index (into `Roadmap.angles`) at every node of the path.
        symbols: one per tick: 0 for a forward move, the bounce angle in degrees for a bump.
        weight: ``w1·ticks + (w2 − w1)·angle_changes``, the Dijkstra distance.
        angle_changes: bumps whose angle differs from the previous bump's (the first is free).
    """

    start: int
    goal: int
    cells: tuple[int, ...]
    layers: tuple[int, ...]
    symbols: tuple[float, ...]
    weight: float
    angle_changes: int

    @property
    def ticks(self) -> int:
        """Number of ticks (edges): forward moves plus bumps."""
        return len(self.symbols)

    @property
    def bumps(self) -> tuple[float, ...]:
        """The bounce angles of the plan, in order (degrees)."""
        return tuple(s for s in self.symbols if s != 0)

    @property
    def distinct_angles(self) -> frozenset[float]:
        """The set of bounce angles the plan uses (the paper's Fig. 7 / 8 statistic)."""
        return frozenset(self.bumps)

    @property
    def leading_zeros(self) -> int:
        """Forward ticks before the first bump (driven by the env's reset in bounce mode)."""
        for n, s in enumerate(self.symbols):
            if s != 0:
                return n
        return len(self.symbols)

    def segments(self) -> list[tuple[float, int]]:
        """``(angle, zeros before it)`` for every bump, in order (the executor's schedule)."""
        out, run = [], 0
        for s in self.symbols:
            if s == 0:
                run += 1
            else:
                out.append((s, run))
                run = 0
        return out

    def __str__(self) -> str:
        """Runs of 0s and angles separated by spaces, e.g. ``000000 135 135 000000 90``."""
        parts, run = [], 0
        for s in self.symbols:
            if s == 0:
                run += 1
                continue
            if run:
                parts.append("0" * run)
                run = 0
            parts.append(f"{s:g}")
        if run:
            parts.append("0" * run)
        return " ".join(parts)


# -- the roadmap ------------------------------------------------------------------------------

class Roadmap:
    """The layered roadmap of a cell model for the bounce angles Φ (see the module docstring).

    Args:
        model: the deterministic cell model (positions x orientation bins).
        angles: Φ in degrees, whole bins of the model, distinct and non-zero modulo 360°.
        w1: weight of a forward move and of a bump that keeps the angle (> 0).
        w2: weight of a bump that changes the angle (>= w1). The paper uses w1 = 1, w2 = 100.

    Attributes:
        graph: the (N·|Φ|) x (N·|Φ|) CSR weight matrix (sorted indices, no duplicate edges).
        edge_kind, edge_angle: per stored edge (aligned with ``graph.data``): `FORWARD` or `BUMP`,
            and the index of the bump's angle in ``angles`` (−1 for forward edges).
        blocked: (N,) the cell's step is blocked: all its edges are bumps, each into the layer
            of its angle.
        dijkstra_calls: number of Dijkstra runs made so far (one per query or start cell).
    """

    def __init__(self, model: CellModel, angles: Iterable[float], w1: float = 1.0,
                 w2: float = 100.0) -> None:
        try:
            degrees = [float(a) for a in angles]
        except (TypeError, ValueError):
            raise ConfigError(f"angles: expected a sequence of angles in degrees, "
                              f"got {angles!r}") from None
        if not degrees or not all(math.isfinite(a) for a in degrees):
            raise ConfigError(f"angles: expected at least one finite angle, got {degrees}")
        bins = [model.angle_bins(math.radians(a), "angles") % model.n_bins for a in degrees]
        if 0 in bins:
            raise ConfigError(f"angles: a multiple of 360° never leaves the wall, got {degrees}")
        if len(set(bins)) != len(bins):
            raise ConfigError(f"angles: expected distinct angles modulo 360°, got {degrees}")
        if not (math.isfinite(w1) and math.isfinite(w2) and w1 > 0 and w2 >= w1):
            raise ConfigError(f"w1, w2: expected 0 < w1 <= w2 (finite), got w1={w1}, w2={w2}")
        self.model = model
        self.angles = tuple(int(a) if a.is_integer() else a for a in degrees)
        self.angle_bins = tuple(bins)
        self.w1, self.w2 = float(w1), float(w2)
        self.n_cells = model.n_cells
        self.n_layers = len(degrees)
        self.n_nodes = self.n_cells * self.n_layers
        self.dijkstra_calls = 0
        self._build()
        self._all: AllPlans | None = None

    def _build(self) -> None:
        model, n, m = self.model, self.n_cells, self.n_layers
        z = np.arange(n, dtype=np.int64)
        p, k = model.decode(z)
        target = model.targets[k, p]
        bump = target < 0
        fz = z[~bump]
        fnext = model.cell_id(target[~bump], k[~bump])
        bz = z[bump]
        rotated = [model.cell_id(p[bump], (k[bump] + b) % model.n_bins) for b in self.angle_bins]
        rows, cols, weight, kind, angle = [], [], [], [], []
        for i in range(m):
            rows.append(i * n + fz)
            cols.append(i * n + fnext)
            weight.append(np.full(len(fz), self.w1))
            kind.append(np.full(len(fz), FORWARD, dtype=np.int8))
            angle.append(np.full(len(fz), -1, dtype=np.int8))
            for j in range(m):
                rows.append(i * n + bz)
                cols.append(j * n + rotated[j])
                weight.append(np.full(len(bz), self.w1 if i == j else self.w2))
                kind.append(np.full(len(bz), BUMP, dtype=np.int8))
                angle.append(np.full(len(bz), j, dtype=np.int8))
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        order = np.lexsort((cols, rows))
        rows, cols = rows[order], cols[order]
        if len(rows) > 1 and np.any((rows[1:] == rows[:-1]) & (cols[1:] == cols[:-1])):
            raise AssertionError("duplicate roadmap edge")  # impossible: distinct layers per bump
        indptr = np.concatenate(([0], np.cumsum(np.bincount(rows, minlength=self.n_nodes))))
        self.graph = sp.csr_matrix((np.concatenate(weight)[order], cols.astype(np.int32),
                                    indptr.astype(np.int32)), shape=(self.n_nodes, self.n_nodes))
        self.edge_kind = np.concatenate(kind)[order]
        self.edge_angle = np.concatenate(angle)[order]
        self.blocked = bump

    # -- nodes and edges ----------------------------------------------------------------------
    def node(self, cell: int, layer: int) -> int:
        """Node number of (cell, active angle index)."""
        return int(layer) * self.n_cells + int(cell)

    def split(self, node) -> tuple[np.ndarray, np.ndarray]:
        """(cell, layer) of node numbers."""
        node = np.asarray(node)
        return node % self.n_cells, node // self.n_cells

    def out_degree(self) -> np.ndarray:
        """Out-degree of every node (|Φ| at bump cells, 1 at forward cells)."""
        return np.diff(self.graph.indptr)

    def edge(self, u: int, v: int) -> int:
        """Index of the stored edge u → v (into ``graph.data``, ``edge_kind``, ``edge_angle``)."""
        g = self.graph
        lo, hi = int(g.indptr[u]), int(g.indptr[u + 1])
        for e in range(lo, hi):
            if g.indices[e] == v:
                return e
        raise KeyError(f"no roadmap edge {u} -> {v}")

    # -- queries ------------------------------------------------------------------------------
    def _search(self, start: int, leave: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """One Dijkstra from all layers of ``start`` (the free first policy); with ``leave``
        from the nodes one edge after them instead (every such edge costs w1 from the best
        layer: a forward move keeps the layer, a bump into layer j leaves from layer j)."""
        sources = [self.node(start, i) for i in range(self.n_layers)]
        if leave:
            g = self.graph
            sources = np.unique(np.concatenate(
                [g.indices[g.indptr[u]:g.indptr[u + 1]] for u in sources])).tolist()
        self.dijkstra_calls += 1
        dist, pred, _ = dijkstra(self.graph, directed=True, indices=sources,
                                 return_predecessors=True, min_only=True)
        return dist, pred

    def _check_cell(self, cell, field: str) -> int:
        if isinstance(cell, bool) or not isinstance(cell, int | np.integer) \
                or not 0 <= int(cell) < self.n_cells:
            raise ConfigError(f"{field}: expected a cell number in [0, {self.n_cells}), "
                              f"got {cell!r}")
        return int(cell)

    def plan(self, start: int, goal: int | Iterable[int], nonempty: bool = False) -> Plan | None:
        """The minimum plan from cell ``start`` to cell ``goal`` (Problem 1), None if none exists.

        ``goal`` may also be a collection of cells (a goal region): the plan ends at the first
        of them it can reach most cheaply. Ties between layers (and goal cells) go to the lowest
        index. ``plan(z, z)`` is the empty plan; with ``nonempty`` the plan takes at least one
        tick (from a goal cell: the cheapest cycle back into the goal region).
        """
        start = self._check_cell(start, "start")
        goals = [self._check_cell(g, "goal") for g in np.atleast_1d(np.asarray(goal)).tolist()]
        if not goals:
            raise ConfigError("goal: expected at least one cell")
        if start in goals and not nonempty:
            return self._empty(start)
        dist, pred = self._search(start, leave=nonempty)
        nodes = np.array([self.node(g, i) for g in goals for i in range(self.n_layers)])
        best = int(nodes[np.argmin(dist[nodes])])
        if not np.isfinite(dist[best]):
            return None
        return self._decode(pred, best, start, first=nonempty)

    def bounce_plan(self, start: int, goal: int | Iterable[int]) -> Plan | None:
        """The minimum plan from ``start`` to ``goal`` that a bounce-mode env counts as arriving.

        In ``step_mode="bounce"`` the env's reset drives the robot from its start to the first
        contact, and the task tests arrival only on the steps after it, each of which starts
        with a bump. The roadmap's forced prefix (the forward edges from ``start`` to the first
        blocked cell) is that drive; a minimum plan without bumps ends in a goal cell on it
        (``start`` itself when start = goal, the paper's NIL plan ``M[i][i]``), where the env
        does not see it. Such a plan is replaced by the drive followed by the minimum plan from
        its blocked end cell that takes at least one tick; None if the goal region cannot be
        entered again after the drive (the start/goal pair is then not solvable in the env).
        """
        plan = self.plan(start, goal)
        if plan is None or plan.bumps:
            return plan
        drive = [plan.start]
        while not self.blocked[drive[-1]]:
            drive.append(self._forward(drive[-1]))
            if len(drive) > self.n_cells:
                raise AssertionError("a straight drive never reached a wall")
        tail = self.plan(drive[-1], goal, nonempty=True)
        if tail is None:
            return None
        run = len(drive) - 1
        return Plan(start=plan.start, goal=tail.goal, cells=(*drive[:-1], *tail.cells),
                    layers=(tail.layers[0],) * run + tail.layers,
                    symbols=(0,) * run + tail.symbols, weight=self.w1 * run + tail.weight,
                    angle_changes=tail.angle_changes)

    def _forward(self, cell: int) -> int:
        """The cell a forward edge leads to from a cell that is not blocked."""
        e = int(self.graph.indptr[cell])  # layer 0: its only edge
        return int(self.graph.indices[e]) % self.n_cells

    def _empty(self, cell: int) -> Plan:
        return Plan(start=cell, goal=cell, cells=(cell,), layers=(0,), symbols=(), weight=0.0,
                    angle_changes=0)

    def _decode(self, pred: np.ndarray, end: int, start: int, first: bool = False) -> Plan:
        """Walk a predecessor tree back from node ``end`` and read the symbols off the edges.

        ``first``: the tree was searched from the nodes one edge after ``start`` (``plan``'s
        ``nonempty``); the edge from ``start`` (in the layer of the node it leads to) is
        prepended."""
        nodes = [end]
        while pred[nodes[-1]] != _NO_PRED:
            nodes.append(int(pred[nodes[-1]]))
            if len(nodes) > self.n_nodes:
                raise AssertionError("cycle in a predecessor tree")
        if first:
            nodes.append(self.node(start, int(self.split(nodes[-1])[1])))
        nodes.reverse()
        symbols, weight, changes = [], 0.0, 0
        for u, v in zip(nodes[:-1], nodes[1:], strict=True):
            e = self.edge(u, v)
            weight += float(self.graph.data[e])
            if self.edge_kind[e] == FORWARD:
                symbols.append(0)
            else:
                symbols.append(self.angles[int(self.edge_angle[e])])
                changes += int(self.split(u)[1] != self.edge_angle[e])
        cells, layers = self.split(np.array(nodes))
        if int(cells[0]) != start:
            raise AssertionError("predecessor path does not start at the start cell")
        return Plan(start=start, goal=int(cells[-1]), cells=tuple(cells.tolist()),
                    layers=tuple(layers.tolist()), symbols=tuple(symbols), weight=weight,
                    angle_changes=changes)

    def all_pairs(self, tree_budget: int = TREE_BUDGET) -> AllPlans:
        """All minimum plans (Alg. 2, line 12 fixed): N Dijkstra runs, one per start cell.

        Keeps the predecessor trees that fit in ``tree_budget`` bytes (at least one; see the
        module docstring, "Memory of all plans"). The result is cached; `plan_between` uses it.
        """
        n, m = self.n_cells, self.n_layers
        capacity = max(1, int(tree_budget) // (4 * self.n_nodes))
        plans = AllPlans(self, np.empty((n, n), dtype=np.float32),
                         np.zeros((n, n), dtype=np.int8), capacity)
        goal_nodes = np.arange(n)[None, :] + n * np.arange(m)[:, None]  # (m, n)
        for s in range(n):
            dist, pred = self._search(s)
            plans.keep(s, pred)
            d = dist[goal_nodes]
            layer = np.argmin(d, axis=0)
            weight = d[layer, np.arange(n)]
            weight[~np.isfinite(weight)] = -1.0  # Alg. 2 lines 11-12 with the test fixed: no path
            weight[s] = 0.0  # lines 1-2: the diagonal stays 0 (and NIL)
            layer[s] = 0
            if plans.L.dtype != weight.dtype and not np.array_equal(
                    weight.astype(plans.L.dtype), weight):
                plans.L = plans.L.astype(weight.dtype)
            plans.L[s] = weight
            plans.end_layer[s] = layer
        self._all = plans
        return plans

    def plan_between(self, i: int, j: int) -> Plan | None:
        """``M[i][j]`` of the all-pairs result (computed on first use), decoded on demand."""
        if self._all is None:
            self.all_pairs()
        return self._all.plan_between(i, j)


class AllPlans:
    """Result of `Roadmap.all_pairs`: weights L, end layers, and some predecessor trees.

    Attributes:
        L: (N, N) plan weights, −1 where no plan exists, 0 on the diagonal; float32 when exact.
        end_layer: (N, N) int8, the active angle index at the goal of each plan.
        capacity: how many predecessor trees are kept (the most recently used).
    """

    def __init__(self, roadmap: Roadmap, L: np.ndarray, end_layer: np.ndarray,
                 capacity: int) -> None:
        self.roadmap = roadmap
        self.L = L
        self.end_layer = end_layer
        self.capacity = capacity
        self._trees: OrderedDict[int, np.ndarray] = OrderedDict()
        self._masks: np.ndarray | None = None

    def keep(self, start: int, tree: np.ndarray) -> None:
        """Store the predecessor tree of ``start``, dropping the least recently used beyond
        ``capacity``."""
        self._trees[start] = tree.astype(np.int32, copy=False)
        self._trees.move_to_end(start)
        while len(self._trees) > self.capacity:
            self._trees.popitem(last=False)

    def predecessors(self, start: int) -> np.ndarray:
        """(N·|Φ|,) int32 Dijkstra predecessor tree of a start cell, searched again if it was
        not kept."""
        tree = self._trees.get(start)
        if tree is None:
            tree = self.roadmap._search(start)[1]
        self.keep(start, tree)
        return self._trees[start]

    def reachable(self) -> np.ndarray:
        """(N, N) bool: a plan exists (the diagonal included)."""
        return self.L >= 0

    def plan_between(self, i: int, j: int) -> Plan | None:
        """``M[i][j]``: the plan from cell i to cell j, None if j is unreachable from i."""
        rm = self.roadmap
        i, j = rm._check_cell(i, "i"), rm._check_cell(j, "j")
        if i == j:
            return rm._empty(i)
        if self.L[i, j] < 0:
            return None
        return rm._decode(self.predecessors(i), rm.node(j, int(self.end_layer[i, j])), i)

    def angle_masks(self) -> np.ndarray:
        """(N, N) bit masks of the angles each plan uses (bit i = ``angles[i]``); 0 where none.

        uint8 up to 8 angles. Computed on the predecessor trees by pointer doubling, a block
        of start cells at a time (kept trees first), without decoding: a tree edge into node
        (z, i) from a blocked cell is a bump with angle i.
        """
        if self._masks is not None:
            return self._masks
        rm = self.roadmap
        n, v = rm.n_cells, rm.n_nodes
        dtype = np.uint8 if rm.n_layers <= 8 else np.int64
        layer_bit = np.left_shift(1, np.arange(v) // n).astype(dtype)
        masks = np.zeros((n, n), dtype=dtype)
        starts = list(self._trees) + [s for s in range(n) if s not in self._trees]
        block = max(1, BLOCK_BYTES // (32 * v))  # about 32 bytes of work per tree node
        for lo in range(0, n, block):
            rows = np.array(starts[lo:lo + block])
            pred = np.stack([self.predecessors(int(s)) for s in rows])
            has = pred >= 0
            bits = np.where(has & rm.blocked[np.where(has, pred, 0) % n], layer_bit,
                            0).astype(dtype).ravel()
            # pointer doubling on the flattened forest: OR the bits of ever farther ancestors
            offset = (np.arange(len(rows)) * v)[:, None]
            anc = (np.where(has, pred, np.arange(v)) + offset).astype(np.int32).ravel()
            while True:
                bits |= bits[anc]
                nxt = anc[anc]
                if np.array_equal(nxt, anc):
                    break
                anc = nxt
            ends = np.arange(n)[None, :] + n * self.end_layer[rows].astype(np.int64)
            masks[rows] = np.take_along_axis(bits.reshape(len(rows), v), ends, axis=1)
        masks[self.L < 0] = 0
        np.fill_diagonal(masks, 0)
        self._masks = masks
        return masks

    def _distinct(self, rows: slice) -> np.ndarray:
        """int8 number of distinct angles of the plans from the start cells ``rows``; −1 where
        there is no plan."""
        masks = self.angle_masks()[rows]
        counts = np.zeros(masks.shape, dtype=np.int8)
        for b in range(self.roadmap.n_layers):
            counts += ((masks >> b) & 1).astype(np.int8)
        counts[self.L[rows] < 0] = -1
        return counts

    def distinct_angle_counts(self) -> np.ndarray:
        """(N, N) int8 number of distinct angles of each plan; −1 where there is no plan."""
        return self._distinct(slice(None))

    def histogram(self) -> dict:
        """Plans of the ordered pairs i ≠ j by number of distinct angles (0..|Φ|), and the
        number of unreachable pairs (key ``"none"``): the statistic of the paper's Figs. 7-8."""
        n, k = self.roadmap.n_cells, self.roadmap.n_layers
        total = np.zeros(k + 2, dtype=np.int64)
        block = max(1, BLOCK_BYTES // (8 * n))
        for lo in range(0, n, block):
            counts = self._distinct(slice(lo, lo + block)).astype(np.int64) + 1
            total += np.bincount(counts.ravel(), minlength=k + 2)
        total[1] -= n  # the diagonal: the empty plans, 0 angles
        out = {c: int(total[c + 1]) for c in range(k + 1)}
        out["none"] = int(total[0])
        return out


# -- goal regions -----------------------------------------------------------------------------

def goal_cells(model: CellModel, position: Sequence[float], heading: float,
               radius: float | None = None, tolerance: float | None = None) -> np.ndarray:
    """Cells of a goal pose: centres within ``radius`` of ``position`` and bin headings within
    ``tolerance`` (radians) of ``heading``. Without a radius or tolerance (or when no cell
    qualifies) the single cell containing the pose (`CellModel.cell_of`) is returned, or an
    empty array if that is not free."""
    if radius is not None and tolerance is not None:
        gap = np.hypot(*(model.centres - np.asarray(position, dtype=np.float64)).T)
        positions = np.flatnonzero(gap <= radius + GOAL_SLACK)
        turn = np.arange(model.n_bins) * model.bin_width - float(heading)
        err = np.abs((turn + math.pi) % (2 * math.pi) - math.pi)
        bins = np.flatnonzero(err <= tolerance + 1e-9)
        if len(positions) and len(bins):
            return np.sort(model.cell_id(positions[None, :], bins[:, None]).ravel())
    z = int(model.cell_of(np.asarray(position, dtype=np.float64)[None], [float(heading)])[0])
    return np.array([z] if z >= 0 else [], dtype=np.int64)


