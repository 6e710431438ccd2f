"""Multi-robot coverage with bouncing robots: the joint simple cell mapping (spec 002 §2, Eq. 6;
thesis Eq. 3.9) and Algorithm 1 / thesis Alg. 3.4 MULTIROBOTCOVERAGE with the resolutions of
spec 002 §8.

**Joint state.** A joint cell is a length-m vector of per-robot cell numbers
``z_i = k_i · N_pos + p_i`` of a `bounce_gym.cells.CellModel` (the package's orientation-major
numbering). Joint cells are never enumerated: batches are ``(batch, m)`` int64 arrays. For small
m, `JointCellModel.encode` gives the mixed-radix joint index ``Σ_i z_i · N^i`` (spec §8.13, with
the package's per-robot numbering instead of the spec's ``pos·8 + θ``).

**Joint map** (Eq. 6 with §8.2–8.4): every robot proposes its king-move target
(``CellModel.targets``); an obstacle target blocks it. With ``collisions=True`` a robot is also
blocked, iterated to a fixpoint, when its target is another moving robot's target, when two
robots would swap cells, or when its target is the cell of a robot that stays. Moving into a cell
that another robot vacates is allowed. Blocked robots stay and rotate CCW by their own φ_i; the
others move and keep their heading. This is exactly `bounce_gym.dynamics.cell_backend.CellBackend`
ticked with ``step_mode="tick"``. A robot–robot collision counts once per colliding pair per step.
``min_sep_cells`` = s > 0 (§8.4, for cells smaller than the robot) widens "the same cell" to
"within Chebyshev distance s" in these rules and in the validity of joint cells.

**Coverage** (§8.5–8.8): follow the joint map while the next joint cell is unprocessed; at a
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

import math
from dataclasses import dataclass, field

import numpy as np

from bounce_gym.cells import CellModel, crowded, resolve_moves, too_close
from bounce_gym.errors import ConfigError

NEIGHBORS = ("rotation", "full")


class JointCellModel:
    """The joint cell map of m bouncing robots on one `CellModel`.

    Args:
        model: the per-robot cell model.
        angles_per_robot: bounce angle φ_i in degrees per robot (a length-m sequence; a scalar
            is not accepted because m is taken from it). Each must be a multiple of the bins.
        collisions: robot–robot collisions block (the coverage task); ``False`` = the robots
            ignore each other and may share cells.
        min_sep_cells: with collisions, the Chebyshev distance at or below which two robots
            collide (0 = the same cell; module docstring).
    """

    def __init__(self, model: CellModel, angles_per_robot, collisions: bool = True,
                 min_sep_cells: int = 0) -> None:
        angles = [float(a) for a in np.atleast_1d(np.asarray(angles_per_robot, dtype=float))]
        if not angles:
            raise ConfigError("angles_per_robot: expected one angle per robot")
        self.model = model
        self.m = len(angles)
        self.angles = angles
        self.phi_bins = np.array([model.angle_bins(math.radians(a), "bounce angle") % model.n_bins
                                  for a in angles], dtype=np.int64)
        if np.any(self.phi_bins == 0):
            raise ConfigError("bounce angle: a multiple of 360° never leaves the wall")
        self.collisions = bool(collisions)
        if self.collisions and model.n_positions < self.m:
            raise ConfigError(f"{self.m} robots do not fit in {model.n_positions} free cells")
        close = too_close(model.position_rc, min_sep_cells)  # validates min_sep_cells
        self.min_sep_cells = int(min_sep_cells)
        self.close = close if self.collisions and self.min_sep_cells > 0 else None
        self.n_robot_cells = model.n_cells
        self.n_joint = model.n_cells ** self.m  # a Python int: may exceed int64

    # -- numbering --------------------------------------------------------------------------
    def encode(self, joint: np.ndarray) -> np.ndarray:
        """Mixed-radix joint index ``Σ_i z_i · N^i`` of joint cells (…, m); needs N^m < 2^63."""
        if self.n_joint >= 2 ** 63:
            raise ConfigError(f"encode: {self.n_robot_cells}^{self.m} joint cells overflow int64; "
                              "use the tuples of per-robot cells")
        radix = self.n_robot_cells ** np.arange(self.m, dtype=np.int64)
        return np.asarray(joint, dtype=np.int64) @ radix

    def decode(self, index: np.ndarray) -> np.ndarray:
        """Joint cells (…, m) of mixed-radix indices."""
        index = np.asarray(index, dtype=np.int64)
        radix = self.n_robot_cells ** np.arange(self.m, dtype=np.int64)
        return (index[..., None] // radix) % self.n_robot_cells

    def index_of(self, joint) -> int:
        """The mixed-radix joint index of one joint cell as a Python int (any m)."""
        n = self.n_robot_cells
        return sum(int(z) * n ** i for i, z in enumerate(joint))

    def from_poses(self, positions, headings_deg) -> np.ndarray:
        """Joint cell (m,) of robot positions (m, 2) and headings in degrees (m,)."""
        z = self.model.cell_of(np.asarray(positions, float), np.radians(headings_deg))
        if np.any(z < 0):
            raise ConfigError("from_poses: a robot is not in a free cell")
        return z

    def valid(self, joint: np.ndarray) -> np.ndarray:
        """Joint cells (batch, m) in X_free: with collisions, no two robots share a position."""
        joint = np.atleast_2d(joint)
        ok = np.all((joint >= 0) & (joint < self.n_robot_cells), axis=1)
        if self.collisions and self.m > 1:
            ok &= ~crowded(np.where(ok[:, None], joint, 0) % self.model.n_positions, self.close)
        return ok

    # -- the map ----------------------------------------------------------------------------
    def plan(self, joint: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(positions, bins, final target or -1, robot-collision pairs per row) of a batch."""
        joint = np.atleast_2d(np.asarray(joint, dtype=np.int64))
        p, k = self.model.decode(joint)
        target0 = self.model.targets[k, p]
        if not self.collisions or self.m == 1:
            return p, k, target0, np.zeros(len(joint), dtype=np.int64)
        stays, _, pairs = resolve_moves(p, target0, self.close)
        return p, k, np.where(stays, -1, target0), pairs

    def step(self, joint: np.ndarray, return_collisions: bool = False):
        """Next joint cells (batch, m) of joint cells (batch, m) or (m,) — Eq. 6.

        With ``return_collisions``, also the number of colliding robot pairs per row.
        """
        joint = np.asarray(joint, dtype=np.int64)
        single = joint.ndim == 1
        p, k, target, pairs = self.plan(joint)
        blocked = target < 0
        new_p = np.where(blocked, p, target)
        new_k = np.where(blocked, (k + self.phi_bins) % self.model.n_bins, k)
        nxt = self.model.cell_id(new_p, new_k)
        if single:
            nxt, pairs = nxt[0], pairs[0]
        return (nxt, pairs) if return_collisions else nxt

    def neighbors(self, joint: np.ndarray, mode: str = "rotation") -> np.ndarray:
        """Valid neighbours (n, m) of one joint cell: ±Δθ of one robot (2m), and with ``"full"``
        also ±1 cell in x or y of one robot (6m at most). Order: robot 0 +Δθ, −Δθ, robot 1 …"""
        if mode not in NEIGHBORS:
            raise ConfigError(f"neighbors: expected one of {NEIGHBORS}, got {mode!r}")
        joint = np.asarray(joint, dtype=np.int64)
        p, k = self.model.decode(joint)
        nb = self.model.n_bins
        out = []
        for i in range(self.m):
            for d in (1, -1):
                q = joint.copy()
                q[i] = self.model.cell_id(p[i], (k[i] + d) % nb)
                out.append(q)
            if mode == "full":
                r, c = self.model.position_rc[p[i]]
                for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0)):
                    rr, cc = r + dr, c + dc
                    if not (0 <= rr < self.model.rows and 0 <= cc < self.model.cols):
                        continue
                    pi = self.model.position_index[rr, cc]
                    if pi < 0:
                        continue
                    q = joint.copy()
                    q[i] = self.model.cell_id(pi, k[i])
                    out.append(q)
        out = np.array(out, dtype=np.int64).reshape(-1, self.m)
        return out[self.valid(out)]

    def random_joint(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Random valid joint cells (n, m): distinct free cells (with collisions; at least
        ``min_sep_cells`` + 1 apart, by rejection), uniform bins."""
        npos = self.model.n_positions
        out = np.empty((n, self.m), dtype=np.int64)
        for row in range(n):
            for _ in range(10_000):
                if self.collisions:
                    p = rng.choice(npos, self.m, replace=False)
                else:
                    p = rng.integers(0, npos, self.m)
                k = rng.integers(0, self.model.n_bins, self.m)
                out[row] = self.model.cell_id(p, k)
                if self.valid(out[row])[0]:
                    break
            else:
                raise ConfigError(f"could not place {self.m} robots min_sep_cells = "
                                  f"{self.min_sep_cells} apart in 10,000 tries")
        return out

    def reachable_positions(self, start_positions) -> np.ndarray:
        """Free position cells reachable by king moves allowed by the corner rule from any of
        ``start_positions`` (a boolean mask over positions)."""
        adj = self.model.targets  # (n_bins, n_positions)
        seen = np.zeros(self.model.n_positions, dtype=bool)
        frontier = np.unique(np.asarray(start_positions, dtype=np.int64))
        seen[frontier] = True
        while len(frontier):
            nxt = adj[:, frontier].ravel()
            nxt = np.unique(nxt[nxt >= 0])
            nxt = nxt[~seen[nxt]]
            seen[nxt] = True
            frontier = nxt
        return seen


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


def _simulate(jm: JointCellModel, starts: np.ndarray, processed: set, keys: _Keys,
              covered: np.ndarray, lookahead: int) -> tuple[np.ndarray, np.ndarray]:
    """Score sequences from ``starts`` (n, m) without marking anything: (new cells, collisions)."""
    n = len(starts)
    npos = jm.model.n_positions
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
        for j, key in zip(idx.tolist(), keys.many(cur[idx]), strict=True):
            if key in processed or key in seen[j]:
                active[j] = False
            else:
                seen[j].add(key)
        idx = np.flatnonzero(active)
        if len(idx) == 0:
            break
        new[rows[idx], cur[idx] % npos] = True
        nxt, pairs = jm.step(cur[idx], return_collisions=True)
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
        while key not in processed and len(traj) - 1 < max_steps:  # §8.1: while unprocessed
            processed.add(key)
            nxt, pairs = jm.step(b, return_collisions=True)
            collisions += int(pairs)
            if steps_to_full is None:
                collisions_to_full += int(pairs)
            b = nxt
            visit(b, "step")
            if stop_at_full and steps_to_full is not None:
                break
            key = keys.one(b)
        if steps_to_full is not None:  # COMPLETECOVERAGE
            checkpoint = None if stop_at_full else len(traj) - 1
            break
        if len(traj) - 1 >= max_steps:
            break
        beta, kind = _best_neighbor(jm, b, neighbors, processed, keys, covered, lookahead, rng)
        if beta is None:
            break
        b = beta
        visit(b, kind)
        if stop_at_full and steps_to_full is not None:
            break
    jumps = [i for i, k in enumerate(kinds) if k != "step"]
    return CoverageResult(traj, kinds, np.array(cov), np.array(cov_all), steps_to_full,
                          checkpoint, collisions, collisions_to_full, visits, n_reach, npos, jumps)


def _best_neighbor(jm, b, mode, processed, keys, covered, lookahead, rng):
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
        new, coll = _simulate(jm, cand, processed, keys, covered, lookahead)
        best = min(range(len(cand)),
                   key=lambda i: (-int(new[i]), int(coll[i]), jm.index_of(cand[i])))
        return cand[best], kind
    for _ in range(1000):  # a random unprocessed valid joint cell
        q = jm.random_joint(rng, 1)[0]
        if keys.one(q) not in processed:
            return q, "random"
    return None, None


def random_start(joint_model: JointCellModel, seed: int) -> np.ndarray:
    """A random initial joint cell (§8.10): distinct free cells, uniform among the 8 bins."""
    return joint_model.random_joint(np.random.default_rng(seed), 1)[0]
