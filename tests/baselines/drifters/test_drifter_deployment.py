"""Alg. 5.2 deployment: coverage, minimality checked by brute force on small fields, and the
random and greedy baselines of the same size."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from baselines.drifters import (
    deployment_locations,
    greedy_deployment,
    group_coverage,
    persistent_behavior,
    random_deployment,
    visit_probabilities,
)
from baselines.drifters.graph import source_components
from bounce_gym.cells import DrifterCells
from bounce_gym.errors import ConfigError
from bounce_gym.flows import FlowField, get_flow


def small_field(seed: int, ny: int = 6, nx: int = 7) -> FlowField:
    """A small open basin with seeded random currents."""
    rng = np.random.default_rng(seed)
    u, v = rng.standard_normal((2, 1, ny, nx))
    return FlowField(u, v, x=np.arange(nx, dtype=float), y=np.arange(ny, dtype=float))


def own_group_reach(b) -> np.ndarray:
    """(n, n) bool: row z = the cells of z's own group that z leads to."""
    label = np.where(b.group_of >= 0, b.group_of, len(b.groups) + b.transient_group_of)
    rows = np.array([b.reach([b.offset + z]) for z in range(b.n_cells)])
    return rows & (label[None, :] == label[:, None])


def test_two_sink_deployment_covers_the_surface_with_one_cell_per_persistent_group():
    model = DrifterCells(get_flow("two_sink"))
    b = persistent_behavior(model)
    dep = deployment_locations(b, seed=3)
    assert len(dep) == 5  # 2 persistent groups + one source component per transient group
    assert group_coverage(b, dep.states).all()
    assert b.reach(dep.states).all()  # the union of the reach sets is the whole surface
    assert [int((b.group_of[dep.states - b.offset] == g).sum()) for g in range(2)] == [1, 1]
    # plain reachability is weaker: one source component of the whole layer leads everywhere
    (source,) = source_components(b.graph, np.arange(b.n_cells))
    assert b.reach(b.offset + source[:1]).all()
    for k in range(len(dep)):  # dropping any cell loses the coverage
        assert not group_coverage(b, np.delete(dep.states, k)).all()
    # same seed, same cells; other seeds move the persistent picks within their groups only
    assert np.array_equal(dep.states, deployment_locations(b, seed=3).states)
    other = deployment_locations(b, seed=4)
    assert np.array_equal(other.states[2:], dep.states[2:])
    assert np.array_equal(b.group_of[other.states[:2]], b.group_of[dep.states[:2]])


@pytest.mark.parametrize("seed", [0, 16, 23, 24])
def test_alg_5_2_is_minimal_by_brute_force(seed):
    model = DrifterCells(small_field(seed), rho=1.0)
    b = persistent_behavior(model)
    dep = deployment_locations(b)
    reach = own_group_reach(b)
    assert reach[dep.states - b.offset].any(axis=0).all()
    k = len(dep)
    assert k >= 3
    # every set of k - 1 cells misses some cell (a smaller set would extend to one that doesn't)
    combos = np.array(list(itertools.combinations(range(b.n_cells), k - 1)))
    assert len(combos) == math.comb(b.n_cells, k - 1)
    for chunk in np.array_split(combos, max(1, len(combos) // 20_000)):
        assert not reach[chunk].any(axis=1).all(axis=1).any()


def test_baselines_have_the_requested_size_and_are_seeded():
    b = persistent_behavior(DrifterCells(get_flow("two_sink")))
    r = random_deployment(b, 5, seed=1)
    assert len(np.unique(r.states)) == 5 and np.array_equal(
        r.states, random_deployment(b, 5, seed=1).states)
    assert not np.array_equal(r.states, random_deployment(b, 5, seed=2).states)
    g = greedy_deployment(b, 5, horizon=30)
    assert len(np.unique(g.states)) == 5 and g.method == "greedy H=30"
    with pytest.raises(ConfigError, match="n"):
        random_deployment(b, 0)
    with pytest.raises(ConfigError, match="horizon"):
        greedy_deployment(b, 2, horizon=-1)


def expected_coverage(hit: np.ndarray, cells) -> float:
    return float((1.0 - np.prod(1.0 - hit[list(cells)], axis=0)).sum())


def test_visit_probabilities_match_monte_carlo():
    model = DrifterCells(get_flow("two_sink"), rho=0.8)
    b = persistent_behavior(model)
    hit = visit_probabilities(b, 12)
    z = int(model.state_of(0, 10, 5))
    rng = np.random.default_rng(0)
    states = np.full(4000, z)
    seen = np.zeros((4000, b.n_cells), dtype=bool)
    seen[:, z] = True
    for _ in range(12):
        states = model.sample(states, np.zeros_like(states), rng)
        seen[np.arange(4000), states] = True
    assert np.abs(seen.mean(axis=0) - hit[z]).max() < 0.03


def test_greedy_is_within_one_minus_one_over_e_of_the_best_set():
    b = persistent_behavior(DrifterCells(small_field(4), rho=0.8))
    hit = visit_probabilities(b, 4)
    best = max(expected_coverage(hit, s) for s in itertools.combinations(range(b.n_cells), 3))
    greedy = expected_coverage(hit, greedy_deployment(b, 3, horizon=4).states - b.offset)
    assert greedy >= (1 - 1 / math.e) * best
    first = greedy_deployment(b, 1, horizon=4).states[0] - b.offset
    assert hit[first].sum() == pytest.approx(hit.sum(axis=1).max())
