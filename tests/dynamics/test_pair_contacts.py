"""The broad phases of robot–robot contacts change nothing: `pair_contacts` returns exactly what
a search over all pairs returns, drives with it are bit-identical to drives with that search, and
`MotionBackend.robot_blockers` equals its all-pairs form.

The references below are the all-pairs forms the backends used before the broad phases (one
(rows x m) table per event), kept verbatim.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.backends import base
from bounce_gym.dynamics.backends.base import pair_contacts
from bounce_gym.dynamics.state import NO_CONTACT
from bounce_gym.worlds import World
from bounce_gym.worlds.raycast import GRAZE


def all_pairs_times(position, velocity, radius, rows):
    """(len(rows), m) first contact times of robot rows[k] with robot j, inf if none."""
    dp = position[rows, None, :] - position[None, :, :]
    dv = velocity[rows, None, :] - velocity[None, :, :]
    a = np.einsum("ijk,ijk->ij", dv, dv)
    b = np.einsum("ijk,ijk->ij", dp, dv)
    c = np.einsum("ijk,ijk->ij", dp, dp) - (2 * radius) ** 2
    disc = b * b - a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / a
    ok = (b < 0) & (disc > a * (GRAZE * 2 * radius) ** 2) & (a > 0)
    t = np.where(ok, np.maximum(t, 0.0), np.inf)
    t[np.arange(len(rows)), rows] = np.inf
    return t


def all_pairs_contacts(position, velocity, radius, horizon):
    """`pair_contacts` by brute force: every pair with a moving robot, no broad phase."""
    rows = np.flatnonzero(np.any(velocity != 0, axis=1))
    table = np.full((len(position), len(position)), np.inf)
    table[rows] = all_pairs_times(position, velocity, radius, rows)
    table = np.minimum(table, table.T)  # a pair of two moving robots appears in both rows
    first, second = np.nonzero(np.triu(table <= horizon, k=1))
    return first, second, table[first, second]


def crowded_scene(seed: int, m: int, radius: float):
    """m robots in a box about twice their total area: near misses, touching pairs, some still."""
    rng = np.random.default_rng(seed)
    side = np.sqrt(2 * m * np.pi * radius**2)
    position = rng.uniform(0, side, (m, 2))
    # a few pairs placed exactly touching, and a few robots at the same x (ties in the sweep)
    for k in range(0, m // 4, 2):
        angle = rng.uniform(0, 2 * np.pi)
        position[k + 1] = position[k] + 2 * radius * np.array([np.cos(angle), np.sin(angle)])
    position[m // 2: m // 2 + 3, 0] = position[m // 2, 0]
    heading = rng.uniform(0, 2 * np.pi, m)
    velocity = np.column_stack((np.cos(heading), np.sin(heading)))
    velocity[rng.random(m) < 0.3] = 0.0
    return position, velocity


@settings(max_examples=60, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31 - 1), m=st.integers(2, 80),
       radius=st.sampled_from([0.05, 0.3, 1.0]),
       horizon=st.sampled_from([0.0, 1e-9, 0.1, 0.7, 3.0, 50.0, np.inf]))
def test_broad_phase_finds_exactly_the_pairs_of_the_all_pairs_search(seed, m, radius, horizon):
    position, velocity = crowded_scene(seed, m, radius)
    got = pair_contacts(position, velocity, radius, horizon)
    want = all_pairs_contacts(position, velocity, radius, horizon)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)  # same pairs, same order, times bit for bit
    assert np.all(got[0] < got[1])


def test_pairs_farther_apart_than_the_window_are_left_out():
    # two robots 10 apart driving at each other touch after (10 - 2R) / 2 = 4.7, not by 4.6
    position = np.array([[0.0, 0.0], [10.0, 0.0], [30.0, 0.0]])
    velocity = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 0.0]])
    assert len(pair_contacts(position, velocity, 0.3, 4.6)[0]) == 0
    first, second, time = pair_contacts(position, velocity, 0.3, 4.8)
    assert (first.tolist(), second.tolist()) == ([0], [1])
    assert time[0] == pytest.approx(4.7)


def _box(side: float) -> World:
    return World([(0, 0), (side, 0), (side, side), (0, side)])


@pytest.mark.parametrize("backend", ["kinematic", "pymunk"])
@pytest.mark.parametrize("mode", ["bounce", "tick"])
def test_drives_with_the_broad_phase_equal_drives_with_all_pairs(monkeypatch, backend, mode):
    """Many robots in a crowded box: every event (time, robots, order) is the same."""
    m, radius = 40, 0.3

    def run():
        dyn = BounceDynamics(_box(9.0), m, backend=backend, physics="ideal", radius=radius,
                             robot_collisions="bounce",
                             noise={"type": "interval", "lo": -0.2, "hi": 0.2})
        state = dyn.reset(np.random.default_rng(3))
        rng = np.random.default_rng(4)
        trace = []
        for _ in range(150 if mode == "bounce" else 400):
            angles = rng.uniform(0.3, 2 * np.pi - 0.3, m)
            if mode == "bounce":
                dyn.bounce(angles)
            else:
                dyn.tick(angles)
            trace.append(np.concatenate((state.position.ravel(), state.heading,
                                         state.contact_robot, state.contact_edge, state.clock,
                                         [state.ticks])))
        return np.array(trace)

    fast = run()
    monkeypatch.setattr(base, "pair_contacts", all_pairs_contacts)
    slow = run()
    np.testing.assert_array_equal(fast, slow)
    assert (fast[:, 3 * m: 4 * m] >= 0).any()  # robots did meet


def all_pairs_blockers(backend, state, robots):
    """`MotionBackend.robot_blockers` over every robot pair."""
    blocker = np.full(len(robots), NO_CONTACT, dtype=np.int64)
    normal = np.zeros((len(robots), 2))
    rel = state.position[None, :, :] - state.position[robots, None, :]  # i -> j
    dist = np.hypot(rel[..., 0], rel[..., 1])
    d = state.direction[robots]
    facing = np.einsum("ik,ijk->ij", d, rel) > GRAZE * np.maximum(dist, 1e-300)
    touching = dist <= 2 * backend.radius + backend.contact_tol
    touching[np.arange(len(robots)), robots] = False
    cand = touching & facing
    has = cand.any(axis=1)
    if np.any(has):
        score = np.where(cand, np.einsum("ik,ijk->ij", d, rel) / np.maximum(dist, 1e-300), -2)
        j = np.argmax(score, axis=1)
        blocker[has] = j[has]
        vec = -rel[np.flatnonzero(has), j[has]]
        normal[has] = vec / np.hypot(vec[:, 0], vec[:, 1])[:, None]
    return blocker, normal


@pytest.mark.parametrize("seed", range(4))
def test_robot_blockers_equal_the_all_pairs_search(seed):
    m = 60
    dyn = BounceDynamics(_box(8.0), m, radius=0.3, robot_collisions="bounce")
    state = dyn.reset(np.random.default_rng(seed))
    rng = np.random.default_rng(seed + 100)
    found = 0
    for _ in range(60):
        dyn.bounce(rng.uniform(0.5, 2 * np.pi - 0.5, m))
        for robots in (np.arange(m), np.flatnonzero(state.blocked), np.array([3, 1])):
            got = dyn.backend.robot_blockers(state, robots)
            want = all_pairs_blockers(dyn.backend, state, robots)
            np.testing.assert_array_equal(got[0], want[0])
            np.testing.assert_array_equal(got[1], want[1])
            found += int((got[0] >= 0).sum())
    assert found > 0
