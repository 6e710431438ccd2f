"""Choosing the bounce angle to localize faster."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from bounce_gym.cells import CellModel
from bounce_gym.errors import ConfigError
from bounce_gym.markov.automata import (
    DFA,
    TRAP,
    ObservationError,
    _knowledge_cycles,
    _read_only,
    _subset_construction,
)
from bounce_gym.markov.filters import _AngleSet


class AngleSwitchPlanner:
    """Reference policy: at a bump, pick the angle minimising the worst-case candidate count.

    A *segment* starts at a bump tick: the robot rotates by the chosen angle, then drives until
    the next bump; its observation is the number k of 0s before that 1 (a 1 right away gives
    k = 0). For a candidate set S at a bump (cells of S that do not bump are dropped — the 1 just
    observed rules them out) and an angle φ, the outcomes partition S into
    ``S'_k = {cells reached at the next bump from the z ∈ S with k zeros}``.

    ``choose(S)`` solves the depth-``depth`` minimax game: the robot picks φ, the world picks the
    outcome k (over the consistent cells), for ``depth`` segments; the value is the candidate
    count at the end (depth 1 = greedy: ``min_φ max_k |S'_k|``). Ties are broken by the expected
    count under a uniform prior over S, then by the order of ``angles``. Results are memoised per
    (set, depth).
    """

    def __init__(self, model: CellModel, angles: Sequence[float], depth: int = 1) -> None:
        if isinstance(depth, bool) or not isinstance(depth, int | np.integer) or depth < 1:
            raise ConfigError(f"depth: expected an integer >= 1, got {depth!r}")
        self._set = _AngleSet(model, angles)
        self.model = model
        self.angles = self._set.angles
        self.depth = int(depth)
        self._run_len, self._run_end = self._forward_runs()
        self._memo: dict[tuple[bytes, int], tuple[int, float, int]] = {}

    def _forward_runs(self) -> tuple[np.ndarray, np.ndarray]:
        """Per cell: 0s until the next bump tick and the cell where it bumps (angle-free)."""
        succ0, bump = self._set.successors[0], self._set.bump
        end = np.arange(self._set.n_cells, dtype=np.int64)
        length = np.zeros(self._set.n_cells, dtype=np.int64)
        for _ in range(self._set.n_cells + 1):
            moving = ~bump[end]
            if not moving.any():
                return length, end
            end[moving] = succ0[end[moving]]
            length[moving] += 1
        raise ConfigError("model: a forward run never bumps")  # pragma: no cover

    def outcomes(self, cells, angle: float) -> dict[int, np.ndarray]:
        """The next-segment outcomes of rotating by ``angle`` at a bump with candidates
        ``cells``: k (number of 0s) → sorted candidate set at the next bump."""
        return self._outcomes(self._bumping(cells), self._set.index(angle))

    def _bumping(self, cells) -> np.ndarray:
        cells = np.unique(np.asarray(cells, dtype=np.int64))
        if cells.size and (cells[0] < 0 or cells[-1] >= self._set.n_cells):
            raise ConfigError(f"cells: expected cell ids in [0, {self._set.n_cells})")
        out = cells[self._set.bump[cells]]
        if out.size == 0:
            raise ObservationError("cells: no candidate cell bumps, so this is not a bump tick")
        return out

    def _outcomes(self, cells: np.ndarray, k: int) -> dict[int, np.ndarray]:
        rotated = self._set.successors[k][cells]
        zeros, ends = self._run_len[rotated], self._run_end[rotated]
        result = {}
        for n in np.unique(zeros).tolist():
            nxt = ends[zeros == n]
            nxt.sort()
            result[int(n)] = nxt
        return result

    def _best(self, cells: np.ndarray, depth: int) -> tuple[int, float, int]:
        key = (cells.tobytes(), depth)
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        best = None
        for k in range(len(self.angles)):
            worst, expected = self._score(cells, k, depth)
            if best is None or (worst, expected) < best[:2]:
                best = (worst, expected, k)
        if len(self._memo) > 200_000:
            self._memo.clear()
        self._memo[key] = best
        return best

    def _score(self, cells: np.ndarray, k: int, depth: int) -> tuple[int, float]:
        worst, expected = 0, 0.0
        for nxt in self._outcomes(cells, k).values():
            if depth == 1:
                w, e = nxt.size, float(nxt.size)
            else:
                w, e, _ = self._best(nxt, depth - 1)
            worst = max(worst, w)
            expected += nxt.size / cells.size * e
        return worst, expected

    def scores(self, cells) -> list[tuple[float, int, float]]:
        """(angle, worst-case count, expected count) of every angle at this planner's depth."""
        bumping = self._bumping(cells)
        return [(a, *self._score(bumping, k, self.depth)) for k, a in enumerate(self.angles)]

    def choose(self, cells) -> float:
        """The angle (radians) to rotate by at this bump, given the candidate set ``cells``."""
        return self.angles[self._best(self._bumping(cells), self.depth)[2]]


def build_policy_dfa(planner: AngleSwitchPlanner, *, max_states: int | None = None) -> DFA:
    """The closed-loop subset automaton of a robot that rotates by ``planner.choose(S)`` at every
    bump — the active counterpart of `build_dfa` (same lazy construction, same knowledge cycles
    and colours), so its localization limits compare directly with the fixed-angle DFAs.
    """
    angle_set = planner._set
    bump, successors = angle_set.bump, angle_set.successors
    chosen: dict[bytes, int] = {}

    def image(cells: np.ndarray, a: int) -> np.ndarray:
        keep = cells[bump[cells] == bool(a)]
        if keep.size == 0:
            return keep
        k = 0
        if a == 1:
            k = chosen[cells.tobytes()] = planner._best(keep, planner.depth)[2]
        out = successors[k][keep]
        out.sort()
        return out

    states, delta, index = _subset_construction(angle_set.n_cells, image, max_states)
    states = _read_only(states)
    angle_index = np.array([chosen.get(s.tobytes(), -1) for s in states], dtype=np.int64)
    angles = np.array(angle_set.angles + (math.nan,))[angle_index]
    cycles, cycle_of, colour = _knowledge_cycles(states, delta)
    return DFA(states=states, delta=delta, n_cells=angle_set.n_cells, periodic=None,
               cycles=cycles, cycle_of=cycle_of, colour=colour, bump_angle=angles,
               bump_angle_index=angle_index, _index=index)


def final_uncertainties(dfa: DFA, successor, bump) -> np.ndarray:
    """The candidate count every start cell ends with: run the true cell and the DFA together
    (closed world) until the DFA is in a knowledge cycle (at most |Q'| steps).

    ``successor`` is the (N,) SCM of a fixed-angle DFA, or the (A, N) stack of the angles of a
    `build_policy_dfa` (the true cell follows the angle the policy picks, row
    ``dfa.bump_angle_index``). The maximum over start cells is the DFA's max uncertainty; the
    mean is the expected final uncertainty under a uniform prior.
    """
    succ = np.atleast_2d(np.asarray(successor, dtype=np.int64))
    obs = np.asarray(bump, dtype=bool)
    n = dfa.n_cells
    cells = np.arange(n, dtype=np.int64)
    states = np.zeros(n, dtype=np.int64)
    choice = dfa.bump_angle_index if dfa.bump_angle_index is not None \
        else np.zeros(dfa.n_states, dtype=np.int64)
    for _ in range(dfa.n_states):
        a = obs[cells]
        row = np.where(a, np.maximum(choice[states], 0), 0)
        cells = succ[row, cells]
        states = dfa.delta[states, a.astype(np.int64)]
    if (states == TRAP).any() or (dfa.cycle_of[states] < 0).any():  # pragma: no cover
        raise AssertionError("a true run left its own world's DFA")
    return dfa.sizes[states]

