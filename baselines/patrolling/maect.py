"""Minimisation of the average expected commute time, MAECT (Alam 2018, thesis §4.4.1, problem
4.4; the effective-resistance problem of Ghosh, Boyd & Saberi 2008).

Edge weights w >= 0 with 1ᵀw = 1 define the weighted Laplacian ``L = A diag(w) Aᵀ`` (eq. 4.2) and
the random walk ``P[i, j] = w_ij / sum_k w_ik``. `maect_objective` is the right-hand side of
eq. 4.3 as printed, ``2/(n-1) sum_{i>=2} 1/λ_i``; for a reversible walk the true mean commute time
over ordered pairs i != j is ``2 (1ᵀw)`` times it (`markov.mean_commute_time` computes that from
hitting times). The printed constant does not move the minimiser.

The strict ``w > 0`` of (4.4) is solved as ``w >= 0``: a weight vector that disconnects the graph
has λ_2 = 0 and an infinite objective, so the optimum stays connected.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import networkx as nx
import numpy as np
import scipy.sparse as sp

from baselines.patrolling.markov import transition_matrix
from bounce_gym.errors import ConfigError

__all__ = ["SOLVERS", "MaectResult", "incidence", "laplacian", "maect_objective",
           "project_simplex", "solve_maect"]

SOLVERS = ("gradient", "cvxpy")
# relative eigenvalue below which λ_2 counts as 0 (disconnected)
_ZERO_EIG = 1e-12
# scaled gradient: the metric weight of an edge is w_e + _SCALE_FLOOR / q
_SCALE_FLOOR = 1e-2


@dataclass(frozen=True)
class MaectResult:
    """A MAECT strategy: edge weights (summing to 1), the walk they define and its objective."""

    weights: dict  # edge (u, v) -> weight, in the order of `edges`
    objective: float  # eq. 4.3 as printed
    transition: sp.csr_array  # row-stochastic, over `nodes`
    nodes: list
    edges: list
    iterations: int


def incidence(graph: nx.Graph, nodes: Sequence | None = None,
              edges: Sequence | None = None) -> sp.csr_array:
    """The oriented incidence matrix A (n x q) of thesis §4.4.1: ``A[i, e] = +1`` if e = (u, v)
    enters i (i = v), ``-1`` if it leaves i (i = u)."""
    nodes = list(graph) if nodes is None else list(nodes)
    edges = list(graph.edges()) if edges is None else list(edges)
    return sp.csr_array(nx.incidence_matrix(graph, nodelist=nodes, edgelist=edges, oriented=True))


def laplacian(A, w) -> np.ndarray:
    """The weighted Laplacian ``L = A diag(w) Aᵀ`` (thesis eq. 4.2), dense."""
    A = sp.csr_array(A)
    w = np.asarray(w, dtype=np.float64)
    if w.shape != (A.shape[1],):
        raise ConfigError(f"w: expected {A.shape[1]} edge weights, got shape {w.shape}")
    return (A @ sp.diags_array(w) @ A.T).toarray()


def maect_objective(A, w) -> float:
    """Thesis eq. 4.3 as printed: ``2/(n-1) sum_{i=2..n} 1/λ_i`` of ``L = A diag(w) Aᵀ``;
    ``inf`` when the weights disconnect the graph."""
    lam = np.linalg.eigvalsh(laplacian(A, w))
    n = len(lam)
    if n < 2:
        raise ConfigError(f"A: the objective needs at least 2 vertices, got {n}")
    if lam[1] <= _ZERO_EIG * max(lam[-1], 1.0):
        return float("inf")
    return float(2.0 / (n - 1) * np.sum(1.0 / lam[1:]))


def project_simplex(v: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """Projection of ``v`` onto {w >= 0, sum w = 1} (sort-and-threshold): Euclidean, or with
    ``scale`` (> 0) the nearest point in the metric ``sum (w - v)² / scale``."""
    c = np.ones_like(v, dtype=np.float64) if scale is None else scale
    ratio = v / c
    order = np.argsort(-ratio, kind="stable")
    threshold = (np.cumsum(v[order]) - 1.0) / np.cumsum(c[order])
    rho = np.flatnonzero(ratio[order] > threshold)[-1]
    return np.maximum(v - threshold[rho] * c, 0.0)


def _objective_and_gradient(A: sp.csr_array, w: np.ndarray) -> tuple[float, np.ndarray]:
    """Eq. 4.3 via ``sum 1/λ_i = tr((L + J/n)⁻¹) - 1`` and its gradient
    ``-2/(n-1) ‖L⁺ a_e‖²`` (Ghosh, Boyd & Saberi 2008, §3)."""
    n = A.shape[0]
    shifted = laplacian(A, w) + 1.0 / n
    try:
        inverse = np.linalg.inv(shifted)
    except np.linalg.LinAlgError:
        return float("inf"), np.zeros_like(w)
    value = 2.0 / (n - 1) * (np.trace(inverse) - 1.0)
    if not np.isfinite(value) or value <= 0 or maect_objective(A, w) == float("inf"):
        return float("inf"), np.zeros_like(w)
    columns = A.T @ inverse  # row e = (L⁺ a_e)ᵀ, since 1ᵀ a_e = 0
    return float(value), -2.0 / (n - 1) * np.einsum("ij,ij->i", columns, columns)


def _projected_gradient(A: sp.csr_array, tol: float, max_iter: int,
                        project: Callable = project_simplex,
                        scaled: bool = False) -> tuple[np.ndarray, int]:
    """Spectral projected gradient (Barzilai-Borwein steps, Armijo backtracking) on the convex
    set that ``project(v, scale)`` projects onto (default: the simplex), started from the
    projection of uniform weights; stops when the objective changes by less than ``tol``
    (relative) and the weights by less than ``sqrt(tol)``. ``scaled``: steps and projections in
    the metric ``sum (Δw_e)² / (w_e + floor)``, which copes with weights of very different sizes
    (problem 4.5)."""
    q = A.shape[1]
    w = project(np.full(q, 1.0 / q), None)
    f, g = _objective_and_gradient(A, w)
    scale = w + _SCALE_FLOOR / q if scaled else None
    c = 1.0 if scale is None else scale
    step = 1.0 / max(np.abs(c * g).max(), 1e-300)
    for iteration in range(1, max_iter + 1):
        direction = project(w - step * c * g, scale) - w
        slope = float(g @ direction)
        t = 1.0
        while True:
            candidate = w + t * direction
            f_new, g_new = _objective_and_gradient(A, candidate)
            if f_new <= f + 1e-4 * t * slope or t < 1e-20:
                break
            t *= 0.5
        s, y = candidate - w, g_new - g
        converged = abs(f - f_new) <= tol * abs(f) and np.abs(s).max() <= np.sqrt(tol)
        w, f, g = candidate, f_new, g_new
        if converged:
            return w, iteration
        sy = float(s @ y)
        step = float(s @ (s / c)) / sy if sy > 0 else step * 2.0
        if scaled:
            scale = w + _SCALE_FLOOR / q
            c = scale
        step = min(max(step, 1e-12), 1e12)
    raise ConfigError(f"max_iter: projected gradient did not converge in {max_iter} iterations")


def _no_constraints(w) -> list:
    return []


def _cvxpy_weights(A: sp.csr_array, constraints: Callable = _no_constraints,
                   project: Callable = project_simplex) -> np.ndarray:
    """The same problem as an SDP: minimise ``tr((L + J/n)⁻¹)`` over the simplex and the extra
    ``constraints(w)`` (cvxpy); the solution is projected (``project``) to clean up round-off."""
    import cvxpy as cp

    n, q = A.shape
    w = cp.Variable(q, nonneg=True)
    dense = A.toarray()
    shifted = dense @ cp.diag(w) @ dense.T + np.full((n, n), 1.0 / n)
    problem = cp.Problem(cp.Minimize(cp.tr_inv(shifted)), [cp.sum(w) == 1, *constraints(w)])
    problem.solve()
    if problem.status != cp.OPTIMAL:
        raise ConfigError(f"solver: cvxpy ended with status {problem.status!r}")
    return project(np.asarray(w.value, dtype=np.float64), None)


def solve_maect(graph: nx.Graph, solver: str = "gradient", tol: float = 1e-12,
                max_iter: int = 100_000) -> MaectResult:
    """Optimal MAECT edge weights of a connected graph (thesis problem 4.4).

    Args:
        graph: an undirected connected graph with at least one edge.
        solver: ``"gradient"`` (projected gradient, numpy) or ``"cvxpy"`` (SDP cross-check).
        tol: relative change of the objective at which the gradient solver stops.
        max_iter: iteration limit of the gradient solver.
    """
    return _solve(graph, solver, tol, max_iter)


def _solve(graph: nx.Graph, solver: str, tol: float, max_iter: int,
           project: Callable = project_simplex, constraints: Callable = _no_constraints,
           scaled: bool = False) -> MaectResult:
    """`solve_maect` over the feasible set that ``project(v, scale)`` projects onto (for the
    gradient solver, with ``scaled`` steps or not) and that the simplex and ``constraints(w)``
    describe (for cvxpy); both default to the simplex alone. ``project`` may depend on the edge
    order ``list(graph.edges())``."""
    if solver not in SOLVERS:
        raise ConfigError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    if graph.number_of_nodes() < 2 or not nx.is_connected(graph):
        raise ConfigError("graph: MAECT needs a connected graph with at least 2 vertices")
    nodes, edges = list(graph), list(graph.edges())
    A = incidence(graph, nodes, edges)
    if solver == "gradient":
        w, iterations = _projected_gradient(A, tol, max_iter, project, scaled)
    else:
        w, iterations = _cvxpy_weights(A, constraints, project), 0
    weights = {e: float(x) for e, x in zip(edges, w, strict=True)}
    P, _ = transition_matrix(graph, weights, nodes)
    return MaectResult(weights=weights, objective=maect_objective(A, w), transition=P,
                       nodes=nodes, edges=edges, iterations=iterations)
