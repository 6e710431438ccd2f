"""Coverage by mixing bouncing policies: the optimal policy distribution α (Alam et al., Alg. 3).

Alam, Bobadilla & Shell, "Minimalist robot navigation and coverage using a dynamical system
approach" (IRC 2017), §IV-C Alg. 3 POLICYDISTRIBUTION, Eq. 4–5, Table I; thesis §3.3.3, Alg. 3.3,
Eq. 3.7–3.8, Table 3.1. Choices where the paper is open: docs/choices/navigation_coverage.md, cited below by heading.

**Coverage Problem.** Given the environment, a set of bouncing angles Φ, an error range ±ε and a
target coverage distribution b, find the bouncing-policy distribution α ("time-based switching
among the bouncing policies": α_i is the proportion of time the robot uses φ_i ± ε) whose
coverage comes closest to b.

* `policy_distributions` — Alg. 3: for every policy φ_i the generalized cell mapping with
  reliability r (the nominal rotation with probability r, each other bin within ±ε with
  (1 − r) / (2 n_ε); ε in whole bins: "ε counts orientation bins"), its persistent groups and its
  long-run distribution π_i, zero on transient cells (`bounce_gym.markov.gcm`). With several
  persistent groups π_i is the Cesàro limit from a uniform start over all cells ("a robot starting
  from any location": "The limiting distribution starts anywhere"; other starts by ``mode``). The
  columns of A are the π_i, over the N cells (``space="cells"``, the paper, n = N) or summed over
  the orientation bins (``space="positions"``, n = N_pos, "Coverage over cells or over positions":
  the coverage of E shown in the paper's heatmaps and measured by
  `bounce_gym.envs.tasks.CoverageTask`).
* `optimal_mixture` — Eq. 5: ``min ‖A α − b‖²  s.t.  Σ α = 1, α ≥ 0`` solved **exactly** by
  enumerating the supports of α (m = |Φ| is small: "Solving Eq. 5 exactly"): on each support S the
  equality-constrained problem ``min ‖A_S x − b‖², 1ᵀx = 1`` is solved through its KKT system
  (null-space method on the QR-compressed problem: no normal equations, so no squared condition
  number; a rank-deficient A_S gets the minimum-norm solution), infeasible (negative) solutions
  are dropped and the smallest residual wins, ties going to the smaller support. The optimum is
  among these candidates: a minimiser with support S is optimal on the affine hull of its face,
  and a degenerate one can be moved along A's null space to a smaller support with the same
  residual. The Lagrange multipliers of the optimum are returned as a certificate.
  ``method="slsqp"`` runs `scipy.optimize.minimize` (SLSQP) instead, for large m.
* `coverage_mixture` — both steps with a target (uniform over the space by default).
* `MixturePolicy` — runs the mixture in a `bounce_gym` env: it switches among the bounce policies
  in epochs of ``epoch`` bumps so that the fraction of **time** (ticks) under φ_i tracks α_i.

**Caveat (docs/choices/navigation_coverage.md, "The mixture's coverage is the model A α").** The paper models the
coverage of the mixture as ``A α``, the convex combination of the single policies' long-run
distributions. A robot that switches policies runs an inhomogeneous chain: each epoch starts where
the last one ended (not from "anywhere"), and with several persistent groups a single run settles in
one group per policy rather than the start- anywhere blend. Simulated coverage approaches ``A α``
only with long epochs and many runs; the benchmark (``python -m benchmarks.coverage``) reports both.

Angles (``angles``, ``eps``) are in **radians**, as everywhere inside the package, and must be whole
multiples of the model's bin width. Cells are numbered as in `bounce_gym.cells.CellModel`
(``z = k · N_pos + p``); position vectors follow ``model.position_rc`` (row-major from the
bottom-left) and `to_grid` maps them to the (rows, cols) grid of `CoverageTask` (row 0 at the
bottom).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from scipy.optimize import minimize

from bounce_gym.errors import ConfigError
from bounce_gym.markov.gcm import gcm

if TYPE_CHECKING:
    from bounce_gym.cells import CellModel

__all__ = [
    "MAX_EXACT",
    "SPACES",
    "MixtureResult",
    "coverage_mixture",
    "mixture_residual",
    "optimal_mixture",
    "policy_distributions",
    "target_vector",
    "to_grid",
]

#: Row spaces of A: the N cells (the paper) or the N_pos positions (the coverage of E).
SPACES = ("cells", "positions")
#: Largest m for the exact support enumeration (2^m - 1 supports of at most m columns).
MAX_EXACT = 16

_FEASIBLE = 1e-10  # a support solution is feasible if every entry is >= -_FEASIBLE
_TIE = 1e-12  # relative residual difference below which the smaller support wins


# -- Alg. 3: the policies' limiting distributions -----------------------------------------------
def policy_distributions(model: CellModel, angles: Sequence[float], eps: float, r: float,
                         space: str = "cells", mode: str | np.ndarray = "all") -> np.ndarray:
    """A (n x m): column i is the long-run distribution π_i of bounce policy ``angles[i]`` ± ε.

    Args:
        model: the cell model (positions x orientation bins).
        angles: the bouncing angles Φ, radians, whole multiples of ``model.bin_width``.
        eps: the error range ε, radians, a whole number of bins (0: exact rotation).
        r: the probability of the nominal (reliable) rotation.
        space: ``"cells"`` (n = N, the paper's Eq. 5) or ``"positions"`` (n = N_pos: π_i summed
            over the orientation bins; docs/choices/navigation_coverage.md, "Coverage over cells or over
            positions").
        mode: the start distribution of the Cesàro limit (`bounce_gym.markov.gcm.MODES` or an (N,)
            probability vector); ``"all"`` is the paper's "starting from any location".

    Every column is >= 0, sums to 1 and (for ``"cells"``) is 0 on the transient cells.
    """
    if space not in SPACES:
        raise ConfigError(f"space: expected one of {SPACES}, got {space!r}")
    phis = np.asarray(angles, dtype=np.float64).reshape(-1)
    if len(phis) == 0 or not np.all(np.isfinite(phis)):
        raise ConfigError(f"angles: expected a non-empty list of finite angles (radians), "
                          f"got {angles!r}")
    columns = [gcm(model, float(phi), eps, r, mode=mode).limiting for phi in phis]
    A = np.column_stack(columns)
    if space == "positions":
        A = A.reshape(model.n_bins, model.n_positions, len(phis)).sum(axis=0)
    return A


def target_vector(model: CellModel, target: object = None, space: str = "cells") -> np.ndarray:
    """The target b over ``space``, normalised to sum 1.

    ``target``: None (uniform over the space: every cell, or every free position), an (n,) vector
    over the space, or a (rows, cols) grid as `CoverageTask` takes (row 0 at the bottom, zero on
    blocked cells); over ``"cells"`` a grid value is split evenly among the orientation bins.
    """
    if space not in SPACES:
        raise ConfigError(f"space: expected one of {SPACES}, got {space!r}")
    n = model.n_cells if space == "cells" else model.n_positions
    if target is None:
        return np.full(n, 1.0 / n)
    b = np.asarray(target, dtype=np.float64)
    if b.shape == model.free.shape:
        if np.any(b[~model.free] != 0):
            raise ConfigError("target: the grid puts mass on blocked cells")
        b = b[model.position_rc[:, 0], model.position_rc[:, 1]]
        if space == "cells":
            b = np.tile(b / model.n_bins, model.n_bins)
    if b.shape != (n,):
        raise ConfigError(f"target: expected shape ({n},) over the {space} or the grid shape "
                          f"{model.free.shape}, got {np.shape(target)}")
    if not np.all(np.isfinite(b)) or np.any(b < 0) or not b.sum() > 0:
        raise ConfigError("target: values must be finite, >= 0, with a positive sum")
    return b / b.sum()


def to_grid(model: CellModel, values: np.ndarray) -> np.ndarray:
    """A vector over the positions (N_pos,) or the cells (N,) as a (rows, cols) grid (summed over
    the bins; 0 on blocked cells), the layout of `CoverageTask` and `World.occupancy`."""
    v = np.asarray(values, dtype=np.float64)
    if v.shape == (model.n_cells,):
        v = v.reshape(model.n_bins, model.n_positions).sum(axis=0)
    if v.shape != (model.n_positions,):
        raise ConfigError(f"values: expected shape ({model.n_positions},) or ({model.n_cells},), "
                          f"got {v.shape}")
    grid = np.zeros(model.free.shape)
    grid[model.position_rc[:, 0], model.position_rc[:, 1]] = v
    return grid


# -- Eq. 5: the constrained least squares ---------------------------------------------------------
@dataclass(eq=False)
class MixtureResult:
    """The optimal policy distribution of Eq. 5 and its certificate.

    Attributes:
        alpha: (m,) the mixture, α >= 0, Σ α = 1.
        residual: ‖A α − b‖², the objective of Eq. 5 (squared L2).
        support: the policies with α_i > 0.
        multiplier: λ of Σ α = 1 and ``dual``: (m,) μ of α >= 0 in the KKT conditions
            ``2 Aᵀ(A α − b) + λ 1 − μ = 0``, μ >= 0, μ_i α_i = 0 (μ = 0 on the support).
        vertex_residuals: (m,) ‖π_i − b‖², the residual of each single policy (α = e_i).
        A, b: the problem (not copied).
        method: ``"exact"`` or ``"slsqp"``.
    """

    alpha: np.ndarray
    residual: float
    support: tuple[int, ...]
    multiplier: float
    dual: np.ndarray
    vertex_residuals: np.ndarray
    A: np.ndarray
    b: np.ndarray
    method: str

    @property
    def distance(self) -> float:
        """‖A α − b‖ (L2, not squared): the analytic counterpart of the env's ``distance``."""
        return math.sqrt(self.residual)

    @property
    def coverage(self) -> np.ndarray:
        """(n,) A α, the modelled coverage of the mixture (Eq. 5)."""
        return self.A @ self.alpha

    def residual_of(self, alpha: np.ndarray) -> float:
        """‖A α − b‖² for any α (e.g. the uniform mixture)."""
        return mixture_residual(self.A, self.b, alpha)


def mixture_residual(A: np.ndarray, b: np.ndarray, alpha: np.ndarray) -> float:
    """‖A α − b‖²."""
    d = np.asarray(A, dtype=np.float64) @ np.asarray(alpha, dtype=np.float64) - b
    return float(d @ d)


def optimal_mixture(A: np.ndarray, b: np.ndarray, method: str = "exact") -> MixtureResult:
    """Solve ``min ‖A α − b‖²  s.t.  Σ α = 1, α >= 0`` (Eq. 5 with C = 1ᵀ, d = 1).

    Args:
        A: (n, m) the policies' distributions as columns (dense or scipy sparse).
        b: (n,) the target.
        method: ``"exact"`` (support enumeration with a KKT solve per support, m <= `MAX_EXACT`;
            see the module docstring) or ``"slsqp"`` (`scipy.optimize.minimize`).

    Raises:
        ConfigError: A is not 2-D with n, m >= 1, b is not (n,), an entry is NaN or infinite,
            ``method`` is unknown, or m > `MAX_EXACT` with ``method="exact"``.
    """
    A, b = _check_problem(A, b)
    n, m = A.shape
    if method not in ("exact", "slsqp"):
        raise ConfigError(f"method: expected 'exact' or 'slsqp', got {method!r}")
    if method == "exact" and m > MAX_EXACT:
        raise ConfigError(f"optimal_mixture: {m} policies means {2**m - 1} supports; the exact "
                          f"method takes m <= {MAX_EXACT}, use method='slsqp'")
    # ‖A α − b‖² = ‖R α − c‖² + ‖b − Q c‖²: every support works on the small (k x m) R
    Q, R = scipy.linalg.qr(A, mode="economic")
    c = Q.T @ b
    scale = float(b @ b + np.max(np.sum(A * A, axis=0)))
    alpha = _enumerate_supports(R, c, scale) if method == "exact" else _slsqp(R, c)
    residual = mixture_residual(A, b, alpha)
    grad = 2.0 * (R.T @ (R @ alpha - c))
    support = tuple(int(i) for i in np.flatnonzero(alpha > 0))
    multiplier = -float(np.mean(grad[list(support)]))
    dual = grad + multiplier
    dual[list(support)] = 0.0
    vertex = np.array([mixture_residual(A, b, e) for e in np.eye(m)])
    return MixtureResult(alpha=alpha, residual=residual, support=support, multiplier=multiplier,
                         dual=dual, vertex_residuals=vertex, A=A, b=b, method=method)


def coverage_mixture(model: CellModel, angles: Sequence[float], eps: float, r: float,
                     target: object = None, space: str = "cells",
                     mode: str | np.ndarray = "all", method: str = "exact") -> MixtureResult:
    """Alg. 3 then Eq. 5: the optimal α for ``target`` (see `target_vector`; uniform by
    default) over ``space``. Angles and ε in radians."""
    A = policy_distributions(model, angles, eps, r, space=space, mode=mode)
    return optimal_mixture(A, target_vector(model, target, space), method=method)


def _check_problem(A, b) -> tuple[np.ndarray, np.ndarray]:
    if sp.issparse(A):
        A = A.toarray()
    try:
        A = np.array(A, dtype=np.float64)
        b = np.array(b, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"optimal_mixture: A and b must be numeric arrays ({exc})") from None
    if A.ndim != 2 or A.shape[0] < 1 or A.shape[1] < 1:
        raise ConfigError(f"A: expected a 2-D (n, m) matrix with n, m >= 1, got shape {A.shape}")
    if b.shape != (A.shape[0],):
        raise ConfigError(f"b: expected shape ({A.shape[0]},) to match A {A.shape}, "
                          f"got {b.shape}")
    if not np.all(np.isfinite(A)):
        raise ConfigError("A: entries must be finite (found NaN or inf)")
    if not np.all(np.isfinite(b)):
        raise ConfigError("b: entries must be finite (found NaN or inf)")
    return A, b


def _support_solution(r_s: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``argmin ‖R_S x − c‖²  s.t.  1ᵀx = 1`` (minimum norm if not unique); ``r_s`` = R_S.

    The KKT system ``[2 R_SᵀR_S, 1; 1ᵀ, 0] [x; λ] = [2 R_Sᵀc; 1]`` solved by the null-space method:
    x = x0 + Z β with x0 = 1/s and Z an orthonormal basis of {1ᵀz = 0}, β the least-squares
    solution of ``R_S Z β = c − R_S x0`` (SVD-based, so rank deficiency is handled)."""
    s = r_s.shape[1]
    x0 = np.full(s, 1.0 / s)
    if s == 1:
        return x0
    basis = scipy.linalg.null_space(np.ones((1, s)))
    beta = scipy.linalg.lstsq(r_s @ basis, c - r_s @ x0)[0]
    return x0 + basis @ beta


def _enumerate_supports(R: np.ndarray, c: np.ndarray, scale: float) -> np.ndarray:
    m = R.shape[1]
    best, best_f = None, math.inf
    tie = _TIE * scale
    for size in range(1, m + 1):  # smaller supports first: they win ties
        for S in itertools.combinations(range(m), size):
            x = _support_solution(R[:, S], c)
            if x.min() < -_FEASIBLE:
                continue
            alpha = np.zeros(m)
            alpha[list(S)] = np.maximum(x, 0.0)
            alpha /= alpha.sum()
            d = R @ alpha - c
            f = float(d @ d)
            if f < best_f - tie:
                best, best_f = alpha, f
    assert best is not None  # every vertex e_i is feasible
    return best


def _slsqp(R: np.ndarray, c: np.ndarray) -> np.ndarray:
    m = R.shape[1]
    # scale the objective to O(1) so SLSQP's absolute tolerance means something
    w = 1.0 / max(float(np.max(np.abs(R))) ** 2, 1e-300)

    def fun(a):
        d = R @ a - c
        return w * float(d @ d), w * 2.0 * (R.T @ d)

    res = minimize(fun, np.full(m, 1.0 / m), jac=True, method="SLSQP",
                   bounds=[(0.0, 1.0)] * m,
                   constraints=[{"type": "eq", "fun": lambda a: np.sum(a) - 1.0,
                                 "jac": lambda a: np.ones_like(a)}],
                   options={"ftol": 1e-15, "maxiter": 1000})
    alpha = np.where(res.x > 1e-12, res.x, 0.0)
    return alpha / alpha.sum()


