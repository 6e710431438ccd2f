"""The patrolling game (Alam 2018, thesis §4.4.2): payoff matrices of Alg. 4.2 and the strong
Stackelberg equilibrium that DOBSS computes (Paruchuri et al. 2008) for one adversary type.

Strategies are rows, the adversary's target vertices columns. Alg. 4.2 ranks the vertices of each
strategy by a "preferred" hitting time h̄ (ascending; values equal to a relative 1e-9, as those
of vertices that a symmetry of the graph swaps, count as ties and keep the lower index first). The
vertex of rank r = 1..n gets ``c_pat = n + 1 - r``, ``c_adv = r`` and ``p = 2^-(r-1)``, and
``P = p c_pat + (1 - p) / n``, ``Q = p c_adv + (1 - p) / n`` with the uniform goods ``1/n``. This
is the algorithm as it must have run to print Table 4.2: the printed exponent ``1/2^(k-2)`` and
line 13 do not give those numbers.

h̄ per strategy (thesis §4.4.2, "HTOFPREFERREDVERTICES"): `preferred_all` (MAECT over all
vertices: the mean hitting time of each vertex from all starts), `preferred_subset` (the clique:
the mean hitting time from each vertex to the subset) and `preferred_towards` (towards vertex i:
the hitting time from each vertex to i).

The leader (patroller) maximises its expected payoff; the follower (adversary) maximises Q, and
breaks ties in the leader's favour (strong Stackelberg). `stackelberg` solves one linear program
per adversary response (scipy HiGHS) and keeps the first response, in index order, whose value is
strictly the best; or, with ``method="dobss"``, the DOBSS mixed-integer program of Paruchuri et
al. (2008) for a single adversary type (scipy `milp`), followed by a second one that picks the
lowest-index response within ``_MILP_TIE`` of its value, so both methods give the same value and,
up to that tolerance, the same response (docs/choices/patrolling.md, "DOBSS and its tie-break"). The
optimal mixture is often not unique (on Table 4.2 any α_7 in [2/7, 73/81] with α_9 = 1 - α_7 is
optimal); ties go to the lexicographically largest mixture (as much weight as possible on the
lowest-index strategy, then the next, ...), which gives Table 4.3.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, linprog, milp

from bounce_gym.errors import ConfigError

__all__ = ["STACKELBERG_METHODS", "StackelbergResult", "payoff_matrices", "preferred_all",
           "preferred_subset", "preferred_towards", "stackelberg"]

STACKELBERG_METHODS = ("lp", "dobss")
# a later response must beat the best value by more than this to replace it
_IMPROVEMENT = 1e-9
# relative difference below which two preferred hitting times tie
_TIE = 1e-9
# slack of the optimal value and of the fixed weights in the lexicographic tie-break
_SLACK = 1e-10
# DOBSS: responses whose value is within this (relative) of the optimum count as tied
_MILP_TIE = 1e-7


def preferred_all(H: np.ndarray) -> np.ndarray:
    """h̄_j = mean_s H[s, j]: how long the walk takes to reach j, averaged over starts."""
    return np.asarray(H, dtype=np.float64).mean(axis=0)


def preferred_subset(H: np.ndarray, subset: Sequence[int]) -> np.ndarray:
    """h̄_j = mean_{s in subset} H[j, s]: how long the walk from j takes to reach the subset."""
    subset = list(subset)
    if not subset:
        raise ConfigError("subset: expected at least one vertex index")
    return np.asarray(H, dtype=np.float64)[:, subset].mean(axis=1)


def preferred_towards(H: np.ndarray, target: int) -> np.ndarray:
    """h̄_j = H[j, target]: how long the walk from j takes to reach the target."""
    return np.asarray(H, dtype=np.float64)[:, target].copy()


def payoff_matrices(preferred: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Alg. 4.2 (corrected): the patroller's and adversary's payoffs ``(P, Q)``, each (k, n),
    from the (k, n) array of h̄ (one row per strategy; ``inf`` allowed, ranked last)."""
    preferred = np.asarray(preferred, dtype=np.float64)
    if preferred.ndim != 2 or preferred.shape[1] < 1 or np.isnan(preferred).any():
        raise ConfigError(f"preferred: expected a (strategies, vertices) array without NaN, got "
                          f"shape {preferred.shape}")
    k, n = preferred.shape
    rank = np.empty((k, n), dtype=np.int64)
    for s, row in enumerate(preferred):
        rank[s, _tied_order(row)] = np.arange(1, n + 1)
    p = 0.5 ** (rank - 1.0)
    goods = 1.0 / n
    return p * (n + 1 - rank) + (1 - p) * goods, p * rank + (1 - p) * goods


def _tied_order(values: np.ndarray) -> np.ndarray:
    """Indices in ascending order of ``values``; near-equal values (``_TIE``) by index."""
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    with np.errstate(invalid="ignore"):  # inf - inf: two unreachable vertices tie
        gap = np.diff(ordered)
        scale = np.maximum(np.abs(ordered[1:]), np.abs(ordered[:-1]))
        close = np.isfinite(gap) & (gap <= _TIE * np.maximum(scale, 1.0))
        new_group = ~(close | (ordered[1:] == ordered[:-1]))
    group = np.concatenate(([0], np.cumsum(new_group)))
    return order[np.lexsort((order, group))]


@dataclass(frozen=True)
class StackelbergResult:
    """The leader's mixed strategy, the follower's response and the leader's value."""

    mixture: np.ndarray  # (k,) probabilities over the strategies (rows)
    attack: int  # column index of the adversary's response
    value: float  # the leader's expected payoff
    follower_value: float


def stackelberg(P: np.ndarray, Q: np.ndarray, method: str = "lp") -> StackelbergResult:
    """The strong Stackelberg equilibrium of the bimatrix game ``(P, Q)`` (leader = rows).

    ``method="lp"``: for each response j, maximise ``αᵀ P[:, j]`` over the simplex subject to
    ``αᵀ (Q[:, j'] - Q[:, j]) <= 0`` for all j'; the best feasible j wins, ties go to the lower
    index. ``method="dobss"``: the DOBSS MILP (`_dobss`). Either way the mixture is then the
    lexicographically largest optimal one for that response.
    """
    if method not in STACKELBERG_METHODS:
        raise ConfigError(f"method: expected one of {STACKELBERG_METHODS}, got {method!r}")
    P = np.asarray(P, dtype=np.float64)
    Q = np.asarray(Q, dtype=np.float64)
    if P.ndim != 2 or P.shape != Q.shape or P.size == 0:
        raise ConfigError(f"P, Q: expected two non-empty matrices of one shape, got {P.shape} "
                          f"and {Q.shape}")
    if not (np.isfinite(P).all() and np.isfinite(Q).all()):
        raise ConfigError("P, Q: payoffs must be finite")
    value, attack = _best_response_lps(P, Q) if method == "lp" else _dobss(P, Q)
    mixture = _lexicographic_mixture(P, Q, attack, value)
    return StackelbergResult(mixture=mixture, attack=attack, value=float(mixture @ P[:, attack]),
                             follower_value=float(mixture @ Q[:, attack]))


def _best_response_lps(P: np.ndarray, Q: np.ndarray) -> tuple[float, int]:
    """The multiple-LP method: the leader's best value and the first response attaining it."""
    k, n = P.shape
    best = None
    for j in range(n):
        solution = linprog(-P[:, j], A_ub=(Q - Q[:, [j]]).T, b_ub=np.zeros(n),
                           A_eq=np.ones((1, k)), b_eq=[1.0], bounds=(0, None), method="highs")
        if solution.status != 0:
            continue  # j is never a best response
        value = -solution.fun
        if best is None or value > best[0] + _IMPROVEMENT:
            best = (value, j)
    return best  # some column is always a best response


def _dobss(P: np.ndarray, Q: np.ndarray) -> tuple[float, int]:
    """DOBSS (Paruchuri et al. 2008, problem (7)) for one adversary type, then the lowest-index
    response whose leader value is within ``_MILP_TIE`` of the optimum.

    Variables ``z[i, j]`` (= α_i q_j, k n of them), the binary response ``q`` (n) and the
    adversary's value ``a``: maximise ``sum P[i, j] z[i, j]`` subject to ``sum z = 1``,
    ``q_j <= sum_i z[i, j] <= 1``, ``sum q = 1`` and
    ``0 <= a - sum_i Q[i, j] α_i <= (1 - q_j) M`` with ``α_i = sum_j z[i, j]`` and ``M`` the
    range of Q.
    """
    k, n = P.shape
    big = float(Q.max() - Q.min()) + 1.0
    size = k * n + n + 1  # z (row-major), q, a
    z_sum = np.zeros((1, size))
    z_sum[0, :k * n] = 1.0
    z_columns = np.zeros((n, size))  # sum_i z[i, j]
    for j in range(n):
        z_columns[j, j:k * n:n] = 1.0
    q = np.zeros((n, size))
    q[:, k * n:k * n + n] = np.eye(n)
    regret = np.zeros((n, size))  # a - Q[:, j]·α
    regret[:, :k * n] = -np.repeat(Q.T, n, axis=1)
    regret[:, -1] = 1.0
    constraints = [LinearConstraint(z_sum, 1.0, 1.0),
                   LinearConstraint(z_columns - q, 0.0, np.inf),
                   LinearConstraint(z_columns, -np.inf, 1.0),
                   LinearConstraint(q.sum(axis=0, keepdims=True), 1.0, 1.0),
                   LinearConstraint(regret, 0.0, np.inf),
                   LinearConstraint(regret + big * q, -np.inf, big)]
    integrality = np.concatenate([np.zeros(k * n), np.ones(n), [0]])
    bounds = Bounds(np.concatenate([np.zeros(k * n + n), [-np.inf]]),
                    np.concatenate([np.full(k * n, np.inf), np.ones(n), [np.inf]]))
    gain = np.concatenate([P.ravel(), np.zeros(n + 1)])
    options = {"mip_rel_gap": 0.0}
    solution = milp(-gain, integrality=integrality, bounds=bounds, constraints=constraints,
                    options=options)
    if solution.status != 0:
        raise ConfigError(f"P, Q: the DOBSS MILP failed ({solution.message})")
    value = -solution.fun
    # among the responses within the tie tolerance of the optimum, the lowest index
    floor = LinearConstraint(gain[None, :], value - _MILP_TIE * max(1.0, abs(value)), np.inf)
    first = np.concatenate([np.zeros(k * n), np.arange(n, dtype=np.float64), [0]])
    solution = milp(first, integrality=integrality, bounds=bounds,
                    constraints=[*constraints, floor], options=options)
    if solution.status != 0:
        raise ConfigError(f"P, Q: the DOBSS tie-break MILP failed ({solution.message})")
    return value, int(np.argmax(solution.x[k * n:k * n + n]))


def _lexicographic_mixture(P: np.ndarray, Q: np.ndarray, attack: int, value: float) -> np.ndarray:
    """Among the mixtures that make ``attack`` a best response with leader value ``value``, the
    lexicographically largest: maximise α_0, fix it, then α_1, ..."""
    k, n = P.shape
    rows = [*(Q - Q[:, [attack]]).T, -P[:, attack]]
    bounds = [0.0] * n + [-(value - _SLACK * max(1.0, abs(value)))]
    mixture = np.zeros(k)
    for s in range(k):
        goal = np.zeros(k)
        goal[s] = -1.0
        solution = linprog(goal, A_ub=np.array(rows), b_ub=np.array(bounds), A_eq=np.ones((1, k)),
                           b_eq=[1.0], bounds=(0, None), method="highs")
        if solution.status != 0:
            raise ConfigError(f"P, Q: the tie-break LP failed ({solution.message})")
        mixture = np.clip(solution.x, 0.0, None)
        fixed = np.zeros(k)
        fixed[s] = -1.0
        rows.append(fixed)
        bounds.append(-(mixture[s] - _SLACK))
    return mixture / mixture.sum()
