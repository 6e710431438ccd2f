"""Exact capture probabilities of an attack under a Markov patrol strategy (Alam 2018, thesis
§4.3.5): p_d(t_a) = Pr[T_detect ≤ t_a], where an attack on target z is caught if some patroller
stands in T_z (the cells seen from z) when it starts or after any of the t_a steps that follow.

The patrollers walk independently on the same chain P. One walker from x avoids T_z for the
whole attack with probability s_{t_a}(x, z), where s_0(x, z) = [x ∉ T_z] and
s_t(x, z) = [x ∉ T_z] Σ_y P[x, y] s_{t-1}(y, z) — the chain restricted to T'_z, t_a steps.
m walkers from x_1..x_m all avoid it with probability Π_i s_{t_a}(x_i, z).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def survival(P: np.ndarray, seen: np.ndarray, attack_time: int) -> np.ndarray:
    """(n, n) array S with ``S[x, z]`` = s_{t_a}(x, z): the probability that one walker on
    ``P`` from vertex x stays out of the watch region T_z (row z of ``seen``) at times
    0, 1, ..., ``attack_time``."""
    outside = ~seen.T  # outside[x, z]: x is not in T_z
    step = sp.csr_array(P)
    S = outside.astype(np.float64)
    for _ in range(attack_time):
        S = outside * (step @ S)
    return S


def capture_from(S: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """(n,) capture probability of an attack on each target that starts with the patrollers
    at ``positions`` (vertex indices)."""
    return 1.0 - np.prod(S[positions], axis=0)


def capture_from_distinct_uniform(S: np.ndarray, m: int) -> np.ndarray:
    """(n,) capture probability of an attack on each target that starts with m patrollers at
    m distinct vertices drawn uniformly (every m-subset equally likely).

    The mean of Π_{x in X} S[x, z] over the m-subsets X is the elementary symmetric polynomial
    e_m(S[:, z]) / C(n, m); it is built one vertex at a time in normalised form,
    a_k(j) = e_k(first j) / C(j, k) = (j - k)/j · a_k(j - 1) + k/j · s_j · a_{k-1}(j - 1),
    a convex combination of numbers in [0, 1], so it cannot overflow.
    """
    n = len(S)
    k = np.arange(1, m + 1)[:, None]
    a = np.zeros((m + 1, S.shape[1]))
    a[0] = 1.0
    for j in range(1, n + 1):
        a[1:] = (j - k) / j * a[1:] + k / j * S[j - 1] * a[:-1]
    return 1.0 - a[m]
