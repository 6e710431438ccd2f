"""``physics="dynamic"``: the stall sensor ends every bounce step.

A robot whose bumper never fires — wedged in a corner or sliding along a wall outside a narrow
bumper arc, pushed by other robots — used to drive forever, and a bounce step never ended. The
wheel overcurrent of the Create 2 stops it: slow for ``stall_time`` while touching something
counts as a bump. Each test below hung before it (the timeouts guard that).
"""

import math
import pickle

import numpy as np
import pytest

from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.backends.pymunk_dynamic import BLOCKED, PHASES
from bounce_gym.worlds import World

SQUARE = World([(0, 0), (10, 0), (10, 10), (0, 10)])
RIGHT, TOP = 1, 2  # edges of SQUARE
pytestmark = pytest.mark.timeout(60)


def narrow(n_robots=1, arc=30.0, world=SQUARE, **params) -> BounceDynamics:
    return BounceDynamics(world, n_robots, backend="pymunk", radius=0.17, physics="dynamic",
                          robot_collisions="bounce" if n_robots > 1 else "ignore",
                          physics_params={"bumper_arc": arc, **params})


def _into_the_corner(**params) -> tuple[BounceDynamics, int]:
    dyn = narrow(**params)
    dyn.reset(np.random.default_rng(0), np.array([[5.0, 5.0]]), np.array([math.pi / 4]))
    return dyn, dyn.drive_to_contact()


def test_a_robot_wedged_in_a_corner_stalls_after_the_stall_time():
    """Both walls touch it 45° off its heading, outside a 30° bumper: it stalls there."""
    dyn, ticks = _into_the_corner()
    state = dyn.state
    assert state.blocked[0] and PHASES[dyn.backend.phase[0]] == "blocked"
    assert state.contact_edge[0] in (RIGHT, TOP)
    np.testing.assert_allclose(state.position[0], [9.83, 9.83], atol=1e-6)
    assert not dyn.backend.bumper_pressed[0]  # the stall, not the bumper
    # 20 s of stall time instead of 1 s: 19 s = 4.75 ticks of 4 s later
    _, later = _into_the_corner(stall_time=20.0)
    assert later - ticks in (4, 5, 6)


def test_a_robot_sliding_too_slowly_along_a_wall_stalls_on_it():
    """40° off the right wall's normal, outside the 30° bumper: it slides up at sin 40° of its
    speed, its wheels rolling at sin² 40° = 0.41 of it: it stalls on the wall (no friction:
    friction would yaw it into the wall, onto its bumper)."""
    dyn = narrow(friction=0.0)
    state = dyn.reset(np.random.default_rng(0), np.array([[5.0, 5.0]]),
                      np.array([math.radians(40)]))
    dyn.drive_to_contact()
    hit = 5.0 + (9.83 - 5.0) * math.tan(math.radians(40))
    assert state.contact_edge[0] == RIGHT
    np.testing.assert_allclose(state.contact_normal[0], [-1.0, 0.0], atol=1e-9)
    assert hit < state.position[0, 1] < 9.83  # slid up, stalled before the corner


def test_a_fast_enough_slide_does_not_stall():
    """80° off the floor's normal, outside a 30° bumper: it slides along the floor, its wheels
    rolling at cos² 10° = 0.97 of its speed, to the right wall, which meets its bumper (no
    friction: friction would yaw it into the floor)."""
    dyn = narrow(arc=30.0, friction=0.0)
    state = dyn.reset(np.random.default_rng(0), np.array([[2.0, 1.0]]),
                      np.array([math.radians(-10)]))
    dyn.drive_to_contact()
    assert state.contact_edge[0] == RIGHT and dyn.backend.bumper_pressed[0]


def test_stalling_repeats_and_every_bounce_ends():
    dyn, _ = _into_the_corner(arc=10.0)
    rng = np.random.default_rng(1)
    for _ in range(100):
        assert dyn.bounce(rng.uniform(0.1, 2 * math.pi - 0.1)) >= 1
    assert dyn.state.bumps[0] == 100


def test_a_push_chain_ends():
    """Three touching robots in a column heading 80°: the top one meets the top wall 10° off
    its heading, outside a 10° bumper, and each robot below meets the one above 10° off too.
    Without friction to yaw them into the wall, the chain presses on at a crawl until it stalls,
    each robot on what is ahead of it; every bounce step after ends as well."""
    dyn = narrow(3, arc=10.0, friction=0.0)
    position = np.array([[5.0, 5.0], [5.0, 5.34], [5.0, 5.68]])
    state = dyn.reset(np.random.default_rng(0), position, np.full(3, math.radians(80)))
    dyn.drive_to_contact()
    assert state.blocked.all() and not dyn.backend.bumper_pressed.any()
    assert list(state.contact_robot[:2]) == [1, 2] and state.contact_edge[2] == TOP
    rng = np.random.default_rng(2)
    for _ in range(30):
        assert dyn.bounce(rng.uniform(0.1, 6.1, 3)) >= 1


def test_a_crowd_with_narrow_bumpers_keeps_bouncing():
    dyn = narrow(8, arc=20.0, world=worlds.get("grid_10x10"), friction=0.0)
    state = dyn.reset(np.random.default_rng(5))
    dyn.drive_to_contact()
    rng = np.random.default_rng(3)
    for _ in range(80):
        dyn.bounce(rng.uniform(0.1, 6.1, 8))
    assert state.bumps.sum() >= 80
    assert dyn.world.contains(state.position, 0.17 * (1 - 1e-4)).all()  # no escape


def test_every_robot_blocked_or_holding_still_ends_the_window():
    """A drive window in which nothing moves passes its ticks without an engine step; a turn
    command turning nobody, or everybody, ends; and the bounce after it ends."""
    dyn = narrow(3, arc=180.0, world=worlds.get("grid_10x10"))
    state = dyn.reset(np.random.default_rng(4))
    for _ in range(200):
        if state.blocked.all():
            break
        dyn.backend.drive(state, 1, until_first_block=False)
    assert state.blocked.all()
    before = state.position.copy()
    assert dyn.backend.drive(state, 3, until_first_block=False) == 3
    assert np.array_equal(state.position, before)
    assert (dyn.backend.phase == BLOCKED).all()
    ticks = state.ticks
    dyn.turn(np.full(3, np.nan))  # nobody turns: every robot holds for one tick
    assert state.ticks == ticks + 1
    dyn.turn(np.full(3, 1.0))
    assert dyn.bounce(np.full(3, 1.0)) >= 1


def test_pickled_while_slow_continues_bit_for_bit():
    dyn = narrow(friction=0.0)
    state = dyn.reset(np.random.default_rng(0), np.array([[5.0, 5.0]]),
                      np.array([math.radians(40)]))
    while dyn.backend._robots[0].stall_at == math.inf:  # until it slides, slow
        dyn.backend.drive(state, 1, until_first_block=False)
    twin = pickle.loads(pickle.dumps(dyn))
    for d in (dyn, twin):
        d.drive_to_contact()
        for angle in (1.0, 2.5, 4.0):
            d.bounce(angle)
    assert twin.state.position.tobytes() == dyn.state.position.tobytes()
    assert twin.state.ticks == dyn.state.ticks
