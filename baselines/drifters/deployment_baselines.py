"""Deployments to compare Alg. 5.2 with, for the same number of drifters: uniformly random water
cells, and a greedy maximisation of the expected number of cells visited within a horizon.

The greedy baseline is not in the thesis. It knows the chain and the horizon and maximises what
a coverage experiment measures: with independent drifters released in the cells S, the expected
number of cells of the layer visited by step H is ``f(S) = Σ_c [1 - Π_{z∈S} (1 - h_H(z, c))]``
where h_H(z, c) is the probability that a drifter released in z visits c within H steps (z
itself at step 0). f is monotone and submodular, so adding the cell of largest gain each time is
within 1 - 1/e of the best set of that size (Nemhauser, Wolsey & Fisher 1978). h_H is computed
exactly for all pairs (H sparse-times-dense products), so the layer is limited to
`MAX_GREEDY_CELLS` cells.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from baselines.drifters.behavior import PersistentBehavior
from baselines.drifters.deployment import Deployment, _check_behavior, _deployment
from baselines.drifters.graph import reachable
from bounce_gym import validate
from bounce_gym.errors import ConfigError

__all__ = ["MAX_GREEDY_CELLS", "expected_coverage", "greedy_deployment", "random_deployment",
           "visit_probabilities"]

#: Largest layer `greedy_deployment` accepts (its pair table is n_cells^2 float64).
MAX_GREEDY_CELLS = 5000


def random_deployment(behavior: PersistentBehavior, n: int, seed: int = 0) -> Deployment:
    """``n`` distinct water cells of the layer drawn uniformly (seeded)."""
    _check_behavior(behavior)
    n = validate.integer("n", n, 1, behavior.n_cells)
    rng = np.random.default_rng(seed)
    return _deployment(behavior.offset + rng.choice(behavior.n_cells, size=n, replace=False),
                       "random")


def visit_probabilities(behavior: PersistentBehavior, horizon: int | None) -> np.ndarray:
    """(n_cells, n_cells) dense: entry (z, c) is the probability that a drifter released in
    cell z of the layer visits cell c within ``horizon`` drift steps (c = z at step 0 counts),
    or ever (``horizon=None``: for each c the absorbing-chain solve ``(I - Q) h = b`` on the
    cells that lead to c, c made absorbing). Layer-local indices."""
    _check_behavior(behavior)
    n = behavior.n_cells
    if n > MAX_GREEDY_CELLS:
        raise ConfigError(f"behavior: the layer has {n} cells; visit probabilities are limited "
                          f"to {MAX_GREEDY_CELLS} cells (an n x n table)")
    P = behavior.graph
    if horizon is None:
        return _eventual_visits(P)
    horizon = validate.integer("horizon", horizon, 0)
    hit = np.eye(n)
    diag = np.arange(n)
    for _ in range(horizon):  # column c: Pr(visit c within k steps), c made absorbing
        hit = P @ hit
        hit[diag, diag] = 1.0
    return hit


def _eventual_visits(P) -> np.ndarray:
    n = P.shape[0]
    hit = np.eye(n)
    P = sp.csr_matrix(P)
    for c in range(n):
        leads = reachable(P, [c], reverse=True)
        leads[c] = False
        t = np.flatnonzero(leads)
        if len(t):  # every cell of t leads to c, so Q = P[t, t] is strictly substochastic
            sub = P[t]
            b = sub[:, [c]].toarray().ravel()
            A = sp.identity(len(t), format="csc") - sub[:, t].tocsc()
            hit[t, c] = np.clip(splu(A).solve(b), 0.0, 1.0)
    return hit


def expected_coverage(behavior: PersistentBehavior, states, hit: np.ndarray) -> float:
    """``f(S) / n_cells`` (module docstring): the expected fraction of the layer's cells that
    independent drifters released in ``states`` (model states of the layer, repeats allowed)
    visit within the horizon of ``hit`` (`visit_probabilities` of the same layer)."""
    _check_behavior(behavior)
    hit = np.asarray(hit)
    if hit.shape != (behavior.n_cells, behavior.n_cells):
        raise ConfigError(f"hit: expected the ({behavior.n_cells}, {behavior.n_cells}) visit "
                          f"probabilities of layer {behavior.layer}, got shape {hit.shape}")
    local = behavior.local(states)
    missed = np.prod(1.0 - hit[local], axis=0)  # Pr(no drifter visits c)
    return float(np.mean(1.0 - missed))


def greedy_deployment(behavior: PersistentBehavior, n: int, horizon: int) -> Deployment:
    """``n`` cells chosen greedily for the expected number of cells visited within ``horizon``
    steps (module docstring); ties go to the lowest state."""
    _check_behavior(behavior)
    n = validate.integer("n", n, 1, behavior.n_cells)
    hit = visit_probabilities(behavior, horizon)
    missed = np.ones(behavior.n_cells)  # Pr(no chosen drifter has visited c)
    chosen: list[int] = []
    available = np.ones(behavior.n_cells, dtype=bool)
    for _ in range(n):
        gain = np.where(available, hit @ missed, -np.inf)
        z = int(np.argmax(gain))
        chosen.append(z)
        available[z] = False
        missed *= 1.0 - hit[z]
    return _deployment(behavior.offset + np.asarray(chosen), f"greedy H={horizon}")
