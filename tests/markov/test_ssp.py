"""Finite-horizon reach values of `ReachPlan` against brute-force enumeration of policies."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from bounce_gym.markov.ssp import ReachPlan


def _chain(seed: int = 0):
    rng = np.random.default_rng(seed)
    n, a = 4, 2
    hit = rng.uniform(0, 0.4, (n, a))
    miss = []
    for i in range(a):
        p = rng.uniform(0, 1, (n, n))
        p *= (1 - hit[:, i] - 0.05)[:, None] / p.sum(axis=1, keepdims=True)  # 5 % get lost
        miss.append(sp.csr_matrix(p))
    return hit, miss, rng.uniform(1, 5, (n, a))


def _brute_success(hit, miss, z: int, h: int) -> float:
    """The best success within h steps, by enumerating every Markov policy (one angle per
    state and step) and evaluating it exactly."""
    n, a = hit.shape
    dense = [m.toarray() for m in miss]
    best = 0.0
    for choice in itertools.product(range(a), repeat=n * h):
        table = np.array(choice).reshape(h, n)  # table[k, s]: the angle with k + 1 steps left
        value = np.zeros(n)
        for k in range(h):
            act = table[k]
            value = np.array([hit[s, act[s]] + dense[act[s]][s] @ value for s in range(n)])
        best = max(best, value[z])
    return best


def test_success_values_are_the_best_over_all_policies():
    hit, miss, cost = _chain()
    plan = ReachPlan(hit, miss, cost, horizon=3)
    for z in range(4):
        for h in (1, 2, 3):
            assert abs(plan.success[h][z] - _brute_success(hit, miss, z, h)) < 1e-12


def test_success_grows_with_the_horizon_and_stays_a_probability():
    hit, miss, cost = _chain(1)
    plan = ReachPlan(hit, miss, cost, horizon=50)
    assert np.all(np.diff(plan.success, axis=0) >= -1e-12)
    assert np.all((plan.success >= 0) & (plan.success <= 1))
    # 5 % of the mass is lost at every step: never certain
    assert plan.success.max() < 1.0


def test_ties_in_success_are_broken_by_plan_cost_and_angle_changes():
    # two angles that both reach the goal surely in one step; angle 1 costs more ticks
    hit = np.array([[1.0, 1.0]])
    miss = [sp.csr_matrix((1, 1)), sp.csr_matrix((1, 1))]
    plan = ReachPlan(hit, miss, np.array([[5.0, 2.0]]), horizon=1, w1=1.0, w2=100.0)
    assert plan.policy[1, 0, 2] == 1  # no angle yet: the cheaper one
    assert plan.policy[1, 0, 0] == 0  # after angle 0: changing costs w2 - w1 more


def test_following_a_receding_horizon_is_evaluated_by_simulating_the_chain():
    """`follow(h, steps)`: the success of always taking the h-step-optimal angle, against a
    Monte Carlo run of that policy on the chain; one step of the 1-step policy is optimal, and
    no stationary policy beats the optimum."""
    hit, miss, cost = _chain(2)
    plan = ReachPlan(hit, miss, cost, horizon=12)
    np.testing.assert_allclose(plan.follow(1, 1)[:, -1], plan.success[1], atol=1e-12)
    assert np.all(plan.follow(12, 12)[:, -1] <= plan.success[12] + 1e-12)
    value = plan.follow(2, 12)
    assert np.all(value <= plan.success[12][:, None] + 1e-12)
    rng = np.random.default_rng(0)
    dense = [m.toarray() for m in miss]
    z0, runs, wins = 1, 20_000, 0
    for _ in range(runs):
        z, last = z0, plan.n_actions
        for _ in range(12):
            a = int(plan.policy[2][z, last])
            u = rng.random()
            if u < hit[z, a]:
                wins += 1
                break
            row = np.cumsum(dense[a][z])
            z = int(np.searchsorted(row, u - hit[z, a], side="right"))
            if z >= len(row):  # lost
                break
            last = a
    assert abs(wins / runs - value[z0, -1]) < 4 * np.sqrt(0.25 / runs)
