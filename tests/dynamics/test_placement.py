"""Random start placement fails fast when robots do not fit, and is unchanged when they do."""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError, InvalidWorldError
from bounce_gym.worlds import World
from bounce_gym.worlds.generators import random_star_polygon


def _comb(teeth: int = 200) -> World:
    """A comb of 1-wide teeth on a 1-high base: 4 * teeth + 2 vertices, nowhere 2 wide."""
    top = []
    for k in reversed(range(teeth)):
        x = 2.0 * k
        top += [(x + 1, 1.0), (x + 1, 11.0), (x, 11.0), (x, 1.0)]
    return World([(0.0, 0.0), (2.0 * teeth - 1, 0.0), *top], name="comb")


@pytest.mark.timeout(30)  # a hang guard only; this took 15-29 s before
def test_more_robots_than_random_placement_can_seat_fail_once_the_room_is_gone():
    env = MultiBounceEnv(n_robots=600)
    with pytest.raises(ConfigError, match=r"n_robots: placed \d+ of 600 robots of robot_radius="
                                          r"0.3 .* no room was left for the next one"):
        env.reset(seed=0)


@pytest.mark.timeout(30)  # a hang guard only; this gave no answer in minutes before
def test_more_robots_than_the_free_space_holds_fail_on_construction():
    with pytest.raises(ConfigError, match=r"n_robots: 5000 robots of robot_radius=0.3 cover .* "
                                          r"at most 664 can fit"):
        MultiBounceEnv(n_robots=5_000)


@pytest.mark.timeout(30)
def test_more_robots_than_an_env_takes_fail_before_any_allocation():
    with pytest.raises(ConfigError, match=r"n_robots: expected an integer in \[1, 10000\], "
                                          r"got 100000"):
        MultiBounceEnv(n_robots=100_000)


@pytest.mark.timeout(30)
def test_large_disks_in_a_star_fail_on_construction():
    star = random_star_polygon(np.random.default_rng(0), n_vertices=200, irregularity=0.01,
                               spikiness=0.3)
    with pytest.raises(ConfigError, match=r"n_robots: 3 robots .* at most 1 can fit"):
        MultiBounceEnv(world=star, n_robots=3, robot_radius=28.0)


@pytest.mark.timeout(30)
def test_large_disks_in_a_star_that_pass_the_area_bound_fail_when_the_room_is_gone():
    star = random_star_polygon(np.random.default_rng(0), n_vertices=200, irregularity=0.01,
                               spikiness=0.05)
    env = MultiBounceEnv(world=star, n_robots=3, robot_radius=50.0)
    with pytest.raises(ConfigError, match=r"placed [12] of 3 robots .* no room was left"):
        env.reset(seed=0)


@pytest.mark.timeout(30)  # a hang guard only; this took 5-26 s before
def test_no_free_space_in_a_comb_is_reported_at_once():
    env = BounceEnv(world=_comb(), robot_radius=2.0)
    with pytest.raises(InvalidWorldError, match=r"no free space for a robot of radius 2.0: the "
                                                "free space shrunk by the radius is empty"):
        env.reset(seed=0)


def test_a_thin_free_space_is_sampled_inside():
    world = _comb()
    env = BounceEnv(world=world, robot_radius=0.45)
    for seed in range(5):
        env.reset(seed=seed)
        assert world.contains(env.core.state.position, 0.45).all()


@pytest.mark.timeout(60)
def test_crowded_but_feasible_placement_succeeds():
    env = MultiBounceEnv(n_robots=300)
    env.reset(seed=0)
    position = env.core.state.position
    gap = np.linalg.norm(position[:, None] - position[None], axis=2)
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= 0.6 - 1e-9
    assert env.options.world.contains(position, 0.3).all()


@pytest.mark.parametrize("kwargs, total, first", [
    ({"n_robots": 4}, 43.51875099032181, [1.7, 3.500584406378923]),
    ({"n_robots": 40}, 623.6327494599154, [1.6999999999999997, 3.4964034587681776]),
    ({"n_robots": 8, "world": "two_rooms", "robot_radius": 0.5}, 142.78883348983203,
     [2.5346430343896897, 2.0310426444801353]),
])
def test_uncrowded_placement_draws_the_same_positions_as_before(kwargs, total, first):
    env = MultiBounceEnv(**kwargs)
    env.reset(seed=3)
    assert env.core.state.position.sum() == total
    assert env.core.state.position[0].tolist() == first


def _count_room_cuts(monkeypatch) -> list:
    """Each crowded round samples the room left once: count those rounds."""
    import bounce_gym.dynamics.backends.base as base

    rounds = []
    sample_in = base.sample_in
    monkeypatch.setattr(base, "sample_in", lambda *a, **k: rounds.append(1) or sample_in(*a, **k))
    return rounds


@pytest.mark.timeout(60)  # a hang guard only
def test_900_robots_that_jam_a_square_fail_after_a_few_rounds_not_one_per_robot(monkeypatch):
    rounds = _count_room_cuts(monkeypatch)
    env = MultiBounceEnv(world="square", n_robots=900, robot_radius=0.14)  # passes the area bound
    with pytest.raises(ConfigError, match=r"^n_robots: placed \d{3} of 900 robots of "
                                          r"robot_radius=0.14 in world 'square' at random"):
        env.reset(seed=0)
    assert 0 < len(rounds) <= 30  # one round per seated robot took 294 (and seconds) before


@pytest.mark.timeout(60)  # a hang guard only
@pytest.mark.parametrize("seed", [0, 1])
def test_900_crowded_robots_that_fit_are_seated_in_a_few_rounds(monkeypatch, seed):
    rounds = _count_room_cuts(monkeypatch)
    env = MultiBounceEnv(world="square", n_robots=900, robot_radius=0.12)
    env.reset(seed=seed)
    position = env.core.state.position
    gap = np.linalg.norm(position[:, None] - position[None], axis=2)
    np.fill_diagonal(gap, np.inf)
    assert gap.min() >= 0.24 - 1e-9 and env.options.world.contains(position, 0.12).all()
    assert 0 < len(rounds) <= 20  # 92 before
