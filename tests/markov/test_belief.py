"""The histogram filter over decision states (`bounce_gym.markov.belief`): its posterior is
Bayes' rule on the sampled table, checked against enumerating every state sequence."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.errors import ConfigError
from bounce_gym.markov.belief import BeliefFilter


def small_world(seed: int = 0, n: int = 4, n_actions: int = 2, samples: int = 5
                ) -> BumpOutcomes:
    """Random sample outcomes over ``n`` states (state 3 has none of its own), ticks 0 … 4,
    some samples lost."""
    rng = np.random.default_rng(seed)
    states = np.arange(n - 1)
    state = np.repeat(states, n_actions * samples)
    action = np.tile(np.repeat(np.arange(n_actions), samples), len(states))
    nxt = rng.integers(-1, n, size=len(state))
    ticks = rng.integers(0, 5, size=len(state))
    zeros = np.zeros((len(state), 2))
    return BumpOutcomes(n, np.linspace(0.5, 2.5, n_actions), state, action, nxt, ticks, zeros,
                        zeros, np.zeros(len(state)))


def dense_table(outcomes: BumpOutcomes) -> np.ndarray:
    """(A, N, N, T) P(z', t | z, a), counted sample by sample."""
    t_max = int(outcomes.ticks.max()) + 1
    out = np.zeros((outcomes.n_actions, outcomes.n_cells, outcomes.n_cells, t_max))
    counts = outcomes.counts()
    for z, a, nz, t in zip(outcomes.state, outcomes.action, outcomes.next_state,
                           outcomes.ticks, strict=True):
        if nz >= 0:
            out[a, z, nz, t] += 1.0 / counts[z, a]
    return out


def likelihood(table, a, z, nz, t, slack, tolerance):
    """L_t(z, z') of the module docstring, from the dense table, one entry at a time."""
    def p(tt):
        return table[a, z, nz, tt] if 0 <= tt < table.shape[3] else 0.0
    tolerant = sum(p(t + d) for d in range(-tolerance, tolerance + 1)) / (2 * tolerance + 1)
    return (1 - slack) * p(t) + slack * tolerant


def brute_force(outcomes, prior, observations, slack, tolerance, restart):
    """Posterior of the last state by summing the joint probability of every state sequence of
    the hidden-Markov model: at each bump the state is first restarted from the prior with
    probability ρ, then moves with likelihood L."""
    table = dense_table(outcomes)
    n = outcomes.n_cells
    post = np.zeros(n)
    for seq in itertools.product(range(n), repeat=len(observations) + 1):
        w = prior[seq[0]]
        for k, (a, t) in enumerate(observations):
            # marginalise the restarted state r between seq[k] and seq[k+1]
            step = sum(((1 - restart) * (r == seq[k]) + restart * prior[r])
                       * likelihood(table, a, r, seq[k + 1], t, slack, tolerance)
                       for r in range(n))
            w *= step
        post[seq[-1]] += w
    return post / post.sum()


@pytest.mark.parametrize("slack, tolerance, restart", [(0.0, 0, 0.0), (0.05, 1, 1e-3),
                                                       (0.3, 2, 0.1)])
def test_posterior_matches_enumerating_every_state_sequence(slack, tolerance, restart):
    outcomes = small_world()
    prior = np.array([0.4, 0.3, 0.2, 0.1])
    bf = BeliefFilter(outcomes, prior=prior, slack=slack, tolerance=tolerance, restart=restart)
    table = dense_table(outcomes)
    rng = np.random.default_rng(1)
    observations = []
    # observations the model can produce: walk a sampled path
    z = 0
    for _ in range(4):
        a = int(rng.integers(outcomes.n_actions))
        options = np.argwhere(table[a, z] > 0) if table[a, z].sum() > 0 else None
        if options is None:
            break
        z, t = (int(v) for v in options[rng.integers(len(options))])
        observations.append((a, t))
        bf.update(a, t)
        expected = brute_force(outcomes, prior, observations, slack, tolerance, restart)
        np.testing.assert_allclose(bf.belief, expected, atol=1e-12)
        assert bf.surprises == 0
        assert bf.most_likely == int(np.argmax(expected))
        assert bf.mass_of([0, 1]) == pytest.approx(expected[0] + expected[1])
    assert len(observations) >= 2


def test_an_unexplained_clock_falls_back_to_the_prediction():
    outcomes = small_world()
    bf = BeliefFilter(outcomes, slack=0.0, tolerance=0, restart=0.0)
    before = bf.belief.copy()
    bf.update(0, 1000)  # no sample drove that long
    prediction = sum(before[z] * dense_table(outcomes)[0, z].sum(axis=1) for z in range(4))
    np.testing.assert_allclose(bf.belief, prediction / prediction.sum())
    assert bf.surprises == 1
    assert np.isclose(bf.belief.sum(), 1.0)


def test_tolerance_keeps_a_state_whose_samples_read_one_tick_off():
    outcomes = small_world()
    table = dense_table(outcomes)
    a, z, nz, t = (int(v) for v in np.argwhere(table > 0)[0])
    # a clock one tick past every sample of (z, a)
    off = int(outcomes.ticks.max()) + 1
    prior = np.eye(4)[z]
    exact = BeliefFilter(outcomes, prior=prior, slack=0.0, tolerance=0, restart=0.0)
    exact.update(a, off)
    assert exact.surprises == 1
    tolerant = BeliefFilter(outcomes, prior=prior, slack=0.1, tolerance=1, restart=0.0)
    tolerant.update(a, off)
    assert tolerant.surprises == 0
    assert np.isclose(tolerant.belief.sum(), 1.0)


def test_expected_entropy_averages_the_posteriors_over_the_ticks():
    outcomes = small_world(seed=3)
    bf = BeliefFilter(outcomes, slack=0.0, tolerance=0, restart=0.0)
    expected = bf.expected_entropy()
    for a in range(outcomes.n_actions):
        total, weighted = 0.0, 0.0
        for t in range(int(outcomes.ticks.max()) + 1):
            probe = BeliefFilter(outcomes, slack=0.0, tolerance=0, restart=0.0)
            joint = dense_table(outcomes)[a, :, :, t].T @ probe.belief
            if joint.sum() <= 0:
                continue
            probe.update(a, t)
            total += joint.sum()
            weighted += joint.sum() * probe.entropy
        assert expected[a] == pytest.approx(weighted / total)


def test_the_belief_is_read_only_and_bad_arguments_are_refused():
    bf = BeliefFilter(small_world())
    with pytest.raises(ValueError):
        bf.belief[0] = 1.0
    with pytest.raises(ConfigError):
        bf.update(5, 1)
    with pytest.raises(ConfigError):
        BeliefFilter(small_world(), slack=1.0)
    with pytest.raises(ConfigError):
        bf.reset(np.zeros(4))
    bf.reset(np.array([0, 0, 1.0, 0]))
    assert bf.most_likely == 2 and bf.max_mass == 1.0
