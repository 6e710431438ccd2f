"""Alam 2018, thesis ch. 5, Algorithm 5.5 POLICYFROMVALUEITERATION: a navigation policy for a
profiling drifter to a goal cell x_G (Problem 4), and the probability that it gets there.

**MDP.** States: every water cell of every layer (the states of `DrifterCells`). Actions
U(x) ⊆ {drift, up, down} (the legal ones; `DrifterCells.legal`): drift follows the layer's GCM row,
up and down move deterministically to the cell above or below. Reward (Eq. 5.10): 100 if the
action leads to x_G, -1 otherwise; under stochastic drift this is the expected reward
``r(x, u) = 100 p(x_G | x, u) - (1 - p(x_G | x, u))``. The goal is absorbing with value 0: the
episode ends there, so nothing is earned by staying (docs/choices/drifters.md, "Alg. 5.5: the goal ends
the episode"). ``goal`` may be a set of cells (a goal region): entering any of them counts.

**Forms.** ``form="thesis"`` iterates the update as printed (Alg. 5.5 line 7),
``V(x) <- γ max_u [r(x, u) + Σ_y p(y | x, u) V(y)]``, and extracts
``π(x) = argmax_u [r(x, u) + Σ_y p(y | x, u) V(y)]`` (line 9); ``form="standard"`` is the
textbook ``V(x) <- max_u [r(x, u) + γ Σ_y p(y | x, u) V(y)]``. The thesis form is the standard
one with reward γ r, so both give the same policy.

**Numerics.** Every update is one sparse product of the stacked (3N, N) action matrix with V.
The iteration runs on ``W = V - s / (1 - γ)``, the value above that of never arriving (s the
step reward, γ r's for the thesis form): then ``W <- max_u [(g - s / (1 - γ)) p(x_G | x, u) +
γ Σ_y p(y | x, u) W(y)]`` (g the goal reward) has no cancellation, stays exactly 0 where the goal
cannot be reached, and is positive however small the probability of arriving, so the policy
picks an action that can arrive wherever one exists. It starts from W = 0, i.e. from
V = r_min / (1 - γ) rather than the thesis' V = r_min (same fixed point; docs/choices/drifters.md,
"Alg. 5.5: iterate above the value of never arriving"), and stops when max |ΔV| < ``tol``.
Ties between actions go to the lowest code (drift, then up, then down).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from baselines.drifters.graph import reachable
from bounce_gym import validate
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.errors import ConfigError

__all__ = ["FORMS", "ValueIterationResult", "goal_states", "policy_matrix", "reach_probability",
           "value_iteration"]

#: The update of Alg. 5.5 as printed, or the textbook one.
FORMS = ("thesis", "standard")


@dataclass(frozen=True, eq=False)
class ValueIterationResult:
    """The output of Alg. 5.5.

    Attributes:
        values: (N,) the converged value V of every state (the thesis' V̂ for
            ``form="thesis"``); 0 on the goal.
        q: (N, 3) what the policy maximises over the actions: ``r + Σ p V`` (thesis form) or
            ``r + γ Σ p V`` (standard form); -inf for illegal actions; 0 for the legal actions
            of a goal state (the episode is over).
        policy: (N,) int64 action codes (0 drift, 1 up, 2 down); drift on the goal.
        goal: the goal states, ascending.
        gamma, form: as given.
        iterations: updates run.
        residual: max |ΔV| of the last update.
        converged: whether ``residual < tol`` was reached within ``max_iterations``.
    """

    values: np.ndarray
    q: np.ndarray
    policy: np.ndarray
    goal: np.ndarray
    gamma: float
    form: str
    iterations: int
    residual: float
    converged: bool


def goal_states(model: DrifterCells, goal) -> np.ndarray:
    """The goal as sorted unique states: a state, a sequence of states, or an (N,) bool mask.

    Raises:
        ConfigError: empty, out of range, or not integers / a mask."""
    arr = np.asarray(goal)
    n = model.n_states
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise ConfigError(f"goal: a mask must have shape ({n},), got {arr.shape}")
        arr = np.flatnonzero(arr)
    elif arr.dtype.kind not in "iu":
        raise ConfigError(f"goal: expected states (integers) or an ({n},) bool mask, got "
                          f"{goal!r}")
    arr = np.unique(arr.astype(np.int64).ravel())
    if len(arr) == 0:
        raise ConfigError("goal: expected at least one state")
    if arr[0] < 0 or arr[-1] >= n:
        raise ConfigError(f"goal: states must lie in [0, {n - 1}], got {arr.tolist()[:5]}")
    return arr


def value_iteration(model: DrifterCells, goal, gamma: float = 0.95, form: str = "thesis",
                    goal_reward: float = 100.0, step_reward: float = -1.0, tol: float = 1e-9,
                    max_iterations: int = 100_000) -> ValueIterationResult:
    """Alg. 5.5 POLICYFROMVALUEITERATION(ℰ, r, γ, x_G) on every state of ``model``
    (module docstring). ``goal``: see `goal_states`.

    Raises:
        ConfigError: a bad argument (γ must lie in (0, 1)).
    """
    if not isinstance(model, DrifterCells):
        raise ConfigError(f"model: expected a DrifterCells, got {type(model).__name__}")
    gamma = validate.number("gamma", gamma, minimum=0.0, strict=True)
    if gamma >= 1:
        raise ConfigError(f"gamma: expected a discount factor in (0, 1), got {gamma!r}")
    if form not in FORMS:
        raise ConfigError(f"form: expected one of {FORMS}, got {form!r}")
    goal_reward = validate.number("goal_reward", goal_reward)
    step_reward = validate.number("step_reward", step_reward)
    tol = validate.number("tol", tol, minimum=0.0, strict=True)
    max_iterations = validate.integer("max_iterations", max_iterations, 1)
    goal = goal_states(model, goal)
    n = model.n_states
    stacked = sp.vstack(model.action_matrices(), format="csr")  # row a * n + x
    at_goal = np.zeros(n)
    at_goal[goal] = 1.0
    p_goal = stacked @ at_goal
    scale = gamma if form == "thesis" else 1.0  # the thesis form earns γ r
    g, s = scale * goal_reward, scale * step_reward
    never = s / (1.0 - gamma)  # the value of never arriving
    base = (g - never) * p_goal
    base[~model.legal.T.ravel()] = -np.inf
    w = np.zeros(n)
    residual, iterations = np.inf, 0
    while iterations < max_iterations:
        iterations += 1
        new = (base + gamma * (stacked @ w)).reshape(3, n).max(axis=0)
        new[goal] = 0.0
        residual = float(np.abs(new - w).max())
        w = new
        if residual < tol:
            break
    q_std = (base + gamma * (stacked @ w)).reshape(3, n).T + never  # r' + γ Σ p V, r' = scale r
    policy = np.argmax(q_std, axis=1)
    policy[goal] = DRIFT
    q = q_std / scale
    q[goal] = np.where(model.legal[goal], 0.0, -np.inf)
    values = w + never
    values[goal] = 0.0
    for arr in (values, q, policy, goal):
        arr.flags.writeable = False
    return ValueIterationResult(values=values, q=q, policy=policy, goal=goal, gamma=gamma,
                                form=form, iterations=iterations, residual=residual,
                                converged=residual < tol)


def policy_matrix(model: DrifterCells, policy, goal=None) -> sp.csr_matrix:
    """(N, N) row-stochastic CSR of the chain under ``policy`` ((N,) action codes); the rows of
    ``goal`` states (if given) are made absorbing.

    Raises:
        ConfigError: wrong shape, unknown codes, or an action illegal where it is used."""
    n = model.n_states
    policy = np.asarray(policy)
    if policy.shape != (n,) or policy.dtype.kind not in "iu":
        raise ConfigError(f"policy: expected ({n},) integer action codes")
    if np.any((policy < 0) | (policy > 2)):
        raise ConfigError("policy: expected action codes 0 (drift), 1 (up), 2 (down)")
    illegal = np.flatnonzero(~model.legal[np.arange(n), policy])
    if len(illegal):
        raise ConfigError(f"policy: {len(illegal)} states have an illegal action, e.g. state "
                          f"{illegal[0]}")
    stacked = sp.vstack(model.action_matrices(), format="csr")
    P = stacked[policy.astype(np.int64) * n + np.arange(n)].tocsr()
    if goal is not None:
        goal = goal_states(model, goal)
        keep = np.ones(n)
        keep[goal] = 0.0
        P = (sp.diags(keep) @ P + sp.csr_matrix((np.ones(len(goal)), (goal, goal)),
                                                shape=(n, n))).tocsr()
    return P


def reach_probability(model: DrifterCells, policy, goal, horizon: int | None = None
                      ) -> np.ndarray:
    """(N,) the probability that the drifter following ``policy`` from each state enters
    ``goal``: ever (``horizon=None``; the absorbing-chain solve ``(I - Q) h = b`` on the states
    that can arrive) or within ``horizon`` steps (1 on the goal itself)."""
    goal = goal_states(model, goal)
    P = policy_matrix(model, policy, goal)
    n = model.n_states
    h = np.zeros(n)
    h[goal] = 1.0
    if horizon is not None:
        horizon = validate.integer("horizon", horizon, 0)
        for _ in range(horizon):
            h = P @ h
        return h
    can = reachable(P, goal, reverse=True)
    can[goal] = False
    t = np.flatnonzero(can)
    if len(t):
        sub = P[t]
        b = np.asarray(sub[:, goal].sum(axis=1)).ravel()
        A = sp.identity(len(t), format="csc") - sub[:, t].tocsc()
        h[t] = np.clip(splu(A).solve(b), 0.0, 1.0)
    return h
