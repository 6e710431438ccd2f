"""Alg. 5.5 value iteration: convergence, the thesis and standard forms, legality, reaching the
goal wherever it can be reached, and the predicted reach probability against simulation."""

from __future__ import annotations

import numpy as np
import pytest

from baselines.drifters import (
    policy_matrix,
    reach_probability,
    three_d_graph,
    value_iteration,
)
from baselines.drifters.graph import reachable
from bounce_gym.cells import DOWN, DRIFT, UP, DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import get_flow


@pytest.fixture(scope="module")
def scb():
    return DrifterCells(get_flow("scb_like"), t=3600.0)


@pytest.fixture(scope="module")
def scb_goal(scb):
    return int(scb.state_of(2, 6, 6))


def test_converges_and_satisfies_the_printed_bellman_equation(scb, scb_goal):
    res = value_iteration(scb, scb_goal)
    assert res.converged and res.residual < 1e-9 and res.form == "thesis"
    free = np.ones(scb.n_states, dtype=bool)
    free[scb_goal] = False
    # V = γ max_u [r + Σ p V] (Alg. 5.5 line 7) and q is that bracket
    assert np.allclose(res.values[free], 0.95 * res.q[free].max(axis=1), atol=1e-7)
    drift, up, down = scb.action_matrices()
    p_goal = drift[:, scb_goal].toarray().ravel()
    r = 100 * p_goal - (1 - p_goal)
    v = res.values
    assert np.allclose(res.q[free, DRIFT], (r + drift @ v)[free], atol=1e-9)
    legal_up = scb.legal[:, UP] & free
    assert np.allclose(res.q[legal_up, UP], (-1 + up @ v)[legal_up], atol=1e-9)
    assert res.values[scb_goal] == 0
    # the goal's neighbours are worth more than cells far from it
    near = drift[scb_goal].indices
    far = np.argsort(res.values)[:10]
    assert res.values[near[near != scb_goal]].min() > res.values[far].max()


def test_illegal_actions_are_never_chosen(scb, scb_goal):
    res = value_iteration(scb, scb_goal)
    assert scb.legal[np.arange(scb.n_states), res.policy].all()
    assert np.isneginf(res.q[~scb.legal]).all() and np.isfinite(res.q[scb.legal]).all()


def test_thesis_form_is_standard_value_iteration_with_reward_gamma_r(scb, scb_goal):
    thesis = value_iteration(scb, scb_goal, gamma=0.9)
    scaled = value_iteration(scb, scb_goal, gamma=0.9, form="standard", goal_reward=90.0,
                             step_reward=-0.9)
    assert np.array_equal(thesis.policy, scaled.policy)
    assert np.allclose(thesis.values, scaled.values, atol=1e-8)
    standard = value_iteration(scb, scb_goal, gamma=0.9, form="standard")
    assert np.array_equal(thesis.policy, standard.policy)  # same policy, values scaled by γ
    assert np.allclose(thesis.values, 0.9 * standard.values, atol=1e-7)
    assert np.allclose(standard.values, standard.q.max(axis=1), atol=1e-7)


def test_uses_up_down_and_drift_on_scb_like(scb, scb_goal):
    res = value_iteration(scb, scb_goal)
    used = np.bincount(res.policy, minlength=3)
    assert (used[[DRIFT, UP, DOWN]] > 0).all()


@pytest.mark.parametrize("name", ["scb_like", "two_sink"])
def test_the_policy_reaches_the_goal_wherever_the_3d_graph_can(name):
    if name == "scb_like":
        model = DrifterCells(get_flow("scb_like"), t=12 * 3600.0)
        goal = int(model.state_of(0, 15, 4))
    else:  # one layer: the cells that only lead to the other persistent group cannot arrive
        model = DrifterCells(get_flow("two_sink"))
        goal = int(model.state_of(0, 13, 10))
    res = value_iteration(model, goal)
    can = reachable(three_d_graph(model), [goal], reverse=True)
    under_policy = reachable(policy_matrix(model, res.policy), [goal], reverse=True)
    assert np.array_equal(under_policy, can)
    h = reach_probability(model, res.policy, goal)
    assert (h[can] > 0).all() and (h[~can] == 0).all()
    assert np.allclose(res.values[~can], 0.95 * -1 / (1 - 0.95))  # never arriving
    if name == "two_sink":
        assert 0 < (~can).sum() < model.n_states


def test_predicted_reach_probability_matches_simulation(scb, scb_goal):
    res = value_iteration(scb, scb_goal)
    horizon = 60
    h = reach_probability(scb, res.policy, scb_goal, horizon=horizon)
    rng = np.random.default_rng(0)
    order = np.argsort(h)
    starts = [order[len(order) // 4], order[len(order) // 2], order[3 * len(order) // 4]]
    for z in starts:
        state = np.full(3000, z)
        arrived = np.zeros(3000, dtype=bool)
        for _ in range(horizon):
            state = np.where(arrived, state, scb.sample(state, res.policy[state], rng))
            arrived |= state == scb_goal
        assert arrived.mean() == pytest.approx(h[z], abs=4 * np.sqrt(0.25 / 3000))
    ever = reach_probability(scb, res.policy, scb_goal)
    longer = reach_probability(scb, res.policy, scb_goal, horizon=1000)
    assert (ever >= longer - 1e-12).all() and (longer >= h - 1e-12).all()
    P = policy_matrix(scb, res.policy, goal=scb_goal)  # the absorbing chain: h = P h
    assert np.allclose(P @ ever, ever, atol=1e-10) and ever[scb_goal] == 1


def test_goal_region_and_bad_input(scb):
    region = scb.state_of(0, [5, 5, 6], [5, 6, 5])
    res = value_iteration(scb, region)
    assert (res.values[region] == 0).all() and res.converged
    assert np.array_equal(res.goal, np.sort(region))
    for kwargs, field in [({"gamma": 1.0}, "gamma"), ({"form": "printed"}, "form"),
                          ({"tol": 0}, "tol"), ({"max_iterations": 0}, "max_iterations")]:
        with pytest.raises(ConfigError, match=field):
            value_iteration(scb, 0, **kwargs)
    for goal in ([], [scb.n_states], 1.5, np.zeros(3, dtype=bool)):
        with pytest.raises(ConfigError, match="goal"):
            value_iteration(scb, goal)
    bad = np.full(scb.n_states, UP)
    with pytest.raises(ConfigError, match="illegal"):
        policy_matrix(scb, bad)
    unconverged = value_iteration(scb, 0, max_iterations=3)
    assert not unconverged.converged and unconverged.iterations == 3
