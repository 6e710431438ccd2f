"""Multi-robot coverage with bouncing robots: the joint simple cell mapping (Alam & Bobadilla
2020, §3.2 and §4.1, Eq. 6; thesis Eq. 3.9) and Algorithm 1 / thesis Alg. 3.4 MULTIROBOTCOVERAGE,
with the choices of docs/choices/multirobot.md where the article is open.

**Joint state.** A joint cell is a length-m vector of per-robot cell numbers
``z_i = k_i · N_pos + p_i`` of a `bounce_gym.cells.CellModel` (the package's orientation-major
numbering). Joint cells are never enumerated: batches are ``(batch, m)`` int64 arrays. For small
m, `JointCellModel.encode` gives the mixed-radix joint index ``Σ_i z_i · N^i`` (docs/choices/multirobot.md,
"Joint cell numbering").

**Joint map** (Eq. 6 with docs/choices/cell_model.md, "Bumps rotate in place and take one tick",
"Diagonal moves and the corner rule" and "Robot–robot conflicts on the grid"): every robot proposes
its king-move target (``CellModel.targets``); an obstacle target blocks it. With ``collisions=True``
a robot is also blocked, iterated to a fixpoint, when its target is another moving robot's target,
when two robots would swap cells, or when its target is the cell of a robot that stays. Moving into
a cell that another robot vacates is allowed. Blocked robots stay and rotate CCW by their own φ_i;
the others move and keep their heading. This is exactly
`bounce_gym.dynamics.backends.cell.CellBackend` ticked with ``step_mode="tick"``. A robot–robot
collision counts once per colliding pair per step. ``min_sep_cells`` = s > 0 (for cells smaller than
the robot) widens "the same cell" to "within Chebyshev distance s" in these rules and in the
validity of joint cells.

**Coverage** (docs/choices/multirobot.md, "The neighbourhood of a joint cell" to "What 'steps to full
coverage' counts"): follow the joint map while the next joint cell is unprocessed; at a
processed cell, if coverage is incomplete, jump to the best unprocessed neighbour — ±Δθ of one
robot's heading (``neighbors="rotation"``, 2m) or also ±1 cell in x or y of one robot
(``"full"``, 6m). Each unprocessed neighbour is simulated (nothing marked) until its sequence
repeats, reaches a processed cell or ``lookahead`` steps; the score is lexicographic: most newly
covered free cells, fewest robot–robot collisions, lowest joint index. Without an unprocessed
neighbour: the 2-ring (two perturbations), then a random unprocessed valid joint cell, else stop.
Coverage is over the free position cells reachable from the start cells (king moves allowed by
the corner rule); the fraction of all free cells is reported too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bounce_gym.cells.joint import NEIGHBORS, JointCellModel
from bounce_gym.errors import ConfigError


@dataclass
class CoverageResult:
    """Output of `plan_coverage`.

    trajectory: joint cells (list of (m,) arrays); ``trajectory[0]`` is the cell of x0.
    edge_kinds: one per edge ``trajectory[t] → trajectory[t+1]``: ``"step"`` (joint map),
        ``"jump"`` (1-ring neighbour), ``"jump2"`` (2-ring), ``"random"`` (random restart).
    coverage: fraction of reachable free positions covered after each joint cell.
    coverage_all: the same over all free positions.
    steps_to_full: transitions until coverage of the reachable cells first reached 1, or None.
    checkpoint_length: transitions when Algorithm 1 checked and found complete coverage.
    collisions: robot–robot collisions (colliding pairs summed over the joint-map steps).
    collisions_to_full: the same up to ``steps_to_full`` (all of them if never full).
    visits: visit counts per position cell (the heatmap).
    n_reachable, n_free: the two coverage denominators.
    """

    trajectory: list
    edge_kinds: list
    coverage: np.ndarray
    coverage_all: np.ndarray
    steps_to_full: int | None
    checkpoint_length: int | None
    collisions: int
    collisions_to_full: int
    visits: np.ndarray
    n_reachable: int
    n_free: int
    jumps: list = field(default_factory=list)  # edge indices that are not joint-map steps

    @property
    def final_coverage(self) -> float:
        return float(self.coverage[-1])


class _Keys:
    """Hashable keys of joint cells: int64 mixed radix when it fits, else tuples."""

    def __init__(self, jm: JointCellModel) -> None:
        self.small = jm.n_joint < 2 ** 63
        self.radix = jm.n_robot_cells ** np.arange(jm.m, dtype=np.int64) if self.small else None

    def many(self, joint: np.ndarray) -> list:
        if self.small:
            return (joint @ self.radix).tolist()
        return list(map(tuple, joint.tolist()))

    def one(self, joint: np.ndarray):
        return self.many(joint[None])[0]


class _Steps:
    """The joint map with memory: the successor and robot–robot collisions of every joint cell
    already stepped in one plan, by key. The candidate simulations walk the sequences that the
    plan then follows, and one another's: each joint cell is stepped once."""

    def __init__(self, jm: JointCellModel) -> None:
        self.jm = jm
        self.known: dict = {}

    def __call__(self, cells: np.ndarray, cell_keys: list) -> tuple[np.ndarray, np.ndarray]:
        """Next joint cells (n, m) and collisions (n,) of joint cells (n, m) with keys."""
        new = [i for i, key in enumerate(cell_keys) if key not in self.known]
        if new:
            nxt, pairs = self.jm.step(cells[new], return_collisions=True)
            for i, cell, n_pairs in zip(new, nxt, pairs.tolist(), strict=True):
                self.known[cell_keys[i]] = cell, n_pairs
        cells, pairs = zip(*map(self.known.__getitem__, cell_keys), strict=True)
        return np.array(cells), np.array(pairs, dtype=np.int64)


def _simulate(steps: _Steps, starts: np.ndarray, processed: set, keys: _Keys,
              covered: np.ndarray, lookahead: int) -> tuple[np.ndarray, np.ndarray]:
    """Score sequences from ``starts`` (n, m) without marking anything: (new cells, collisions)."""
    n = len(starts)
    npos = steps.jm.model.n_positions
    new = np.zeros((n, npos), dtype=bool)
    coll = np.zeros(n, dtype=np.int64)
    seen = [set() for _ in range(n)]
    active = np.ones(n, dtype=bool)
    cur = starts.copy()
    rows = np.arange(n)[:, None]
    for _ in range(lookahead):
        idx = np.flatnonzero(active)
        if len(idx) == 0:
            break
        active_keys = []
        for j, key in zip(idx.tolist(), keys.many(cur[idx]), strict=True):
            if key in processed or key in seen[j]:
                active[j] = False
            else:
                seen[j].add(key)
                active_keys.append(key)
        idx = np.flatnonzero(active)
        if len(idx) == 0:
            break
        new[rows[idx], cur[idx] % npos] = True
        nxt, pairs = steps(cur[idx], active_keys)
        coll[idx] += pairs
        cur[idx] = nxt
    return (new & ~covered).sum(axis=1), coll


def plan_coverage(joint_model: JointCellModel, x0, max_steps: int = 10_000,
                  neighbors: str = "rotation", lookahead: int = 300, max_parts: int = 10_000,
                  seed: int = 0, stop_at_full: bool = False) -> CoverageResult:
    """Algorithm 1 (MULTIROBOTCOVERAGE) from the joint cell ``x0`` (m,) — see the module
    docstring. ``max_steps`` caps the transitions, ``max_parts`` the parts (L), ``lookahead``
    the simulation of each candidate neighbour; ``seed`` drives the random fallback.

    Algorithm 1 checks coverage only at the end of a part, so by default the part in which
    coverage completes is followed to its end (``checkpoint_length``); ``stop_at_full`` stops
    at the first full-coverage step instead (same ``steps_to_full``, less work)."""
    jm = joint_model
    if neighbors not in NEIGHBORS:
        raise ConfigError(f"neighbors: expected one of {NEIGHBORS}, got {neighbors!r}")
    b = np.asarray(x0, dtype=np.int64).reshape(jm.m)
    if not jm.valid(b)[0]:
        raise ConfigError("x0: not a valid joint cell (out of range or two robots share a cell)")
    rng = np.random.default_rng(seed)
    npos = jm.model.n_positions
    keys = _Keys(jm)
    steps = _Steps(jm)
    reach = jm.reachable_positions(b % npos)
    n_reach = int(reach.sum())
    covered = np.zeros(npos, dtype=bool)
    visits = np.zeros(npos, dtype=np.int64)
    processed: set = set()
    traj, kinds, cov, cov_all = [], [], [], []
    steps_to_full = checkpoint = None
    collisions = 0
    collisions_to_full = 0

    def visit(cell: np.ndarray, kind: str | None) -> None:
        nonlocal steps_to_full
        traj.append(cell)
        if kind is not None:
            kinds.append(kind)
        p = cell % npos
        covered[p] = True
        np.add.at(visits, p, 1)
        n_cov = int(covered[reach].sum())
        cov.append(n_cov / n_reach)
        cov_all.append(int(covered.sum()) / npos)
        if steps_to_full is None and n_cov == n_reach:
            steps_to_full = len(traj) - 1

    visit(b, None)
    for _ in range(max_parts):
        key = keys.one(b)
        while key not in processed and len(traj) - 1 < max_steps:  # while unprocessed
            processed.add(key)
            nxt, pairs = steps(b[None], [key])
            collisions += int(pairs[0])
            if steps_to_full is None:
                collisions_to_full += int(pairs[0])
            b = nxt[0]
            visit(b, "step")
            if stop_at_full and steps_to_full is not None:
                break
            key = keys.one(b)
        if steps_to_full is not None:  # COMPLETECOVERAGE
            checkpoint = None if stop_at_full else len(traj) - 1
            break
        if len(traj) - 1 >= max_steps:
            break
        beta, kind = _best_neighbor(steps, b, neighbors, processed, keys, covered, lookahead,
                                    rng)
        if beta is None:
            break
        b = beta
        visit(b, kind)
        if stop_at_full and steps_to_full is not None:
            break
    jumps = [i for i, k in enumerate(kinds) if k != "step"]
    return CoverageResult(traj, kinds, np.array(cov), np.array(cov_all), steps_to_full,
                          checkpoint, collisions, collisions_to_full, visits, n_reach, npos, jumps)


def _best_neighbor(steps, b, mode, processed, keys, covered, lookahead, rng):
    jm = steps.jm
    for kind in ("jump", "jump2"):
        if kind == "jump":
            cand = jm.neighbors(b, mode)
        else:
            ring1 = jm.neighbors(b, mode)
            cand = [jm.neighbors(q, mode) for q in ring1]
            cand = np.unique(np.concatenate(cand), axis=0) if cand else np.empty((0, jm.m), int)
            cand = cand[np.any(cand != b, axis=1)]
        if len(cand) == 0:
            continue
        ck = keys.many(cand)
        keep = np.array([k not in processed for k in ck], dtype=bool)
        cand = cand[keep]
        if len(cand) == 0:
            continue
        new, coll = _simulate(steps, cand, processed, keys, covered, lookahead)
        best = min(range(len(cand)),
                   key=lambda i: (-int(new[i]), int(coll[i]), jm.index_of(cand[i])))
        return cand[best], kind
    for _ in range(1000):  # a random unprocessed valid joint cell
        q = jm.random_joint(rng, 1)[0]
        if keys.one(q) not in processed:
            return q, "random"
    return None, None


def random_start(joint_model: JointCellModel, seed: int) -> np.ndarray:
    """A random initial joint cell (docs/choices/multirobot.md, "Random initial joint cells"): distinct free
    cells, uniform among the 8 bins."""
    return joint_model.random_joint(np.random.default_rng(seed), 1)[0]
