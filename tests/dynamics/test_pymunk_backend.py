"""The pymunk backend against the exact kinematic backend: same contacts, no escape, determinism."""

import pickle

import numpy as np
import pytest

from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.backends.pymunk import PymunkBackend
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World, parse_ascii, world_from_grid

SQUARE = World([(0, 0), (10, 0), (10, 10), (0, 10)], name="square")
L_SHAPE = World([(0, 0), (12, 0), (12, 5), (5, 5), (5, 12), (0, 12)], name="L")
HEPTAGON = World(
    [(450, 150), (650, 420), (425, 500), (200, 480), (50, 270), (170, 80), (300, 50)],
    name="heptagon",
)
HOLED = World(
    [(0, 0), (20, 0), (20, 12), (11, 12), (11, 16), (0, 16)],
    [[(3, 3), (6, 3), (5, 7)], [(12, 2), (16, 2), (16, 5), (12, 5)]],
    name="nonconvex with holes",
)
GRID = world_from_grid(
    parse_ascii(
        [
            "##########",
            "#....#...#",
            "#.##.#.#.#",
            "#.##...#.#",
            "#......#.#",
            "####.....#",
            "##########",
        ]
    ),
    name="grid",
)


def _pair(world, seed, radius=0.0, **kwargs):
    """The same random start (irrational pose) on both backends."""
    rng = np.random.default_rng(seed)
    pos = world.sample_free(rng, 1, radius)
    heading = rng.uniform(0, 2 * np.pi, 1)
    out = []
    for backend in ("kinematic", "pymunk"):
        dyn = BounceDynamics(world, backend=backend, physics="ideal", radius=radius, **kwargs)
        dyn.reset(np.random.default_rng(0), position=pos, heading=heading)
        out.append(dyn)
    return out


ZOO = ["square", "l_shape", "heptagon", "two_rooms", "simple_bit", "pinched_square",
       "lab_navigation", "grid_15x15"]
WORLDS = [worlds.get(name) for name in ZOO] + [HOLED, GRID]


@pytest.mark.parametrize("world", WORLDS, ids=lambda w: w.name)
@pytest.mark.parametrize("radius_fraction", [0.0, 0.02])
def test_agrees_with_kinematic_backend(world, radius_fraction):
    """Issue #2: the two backends hit the same walls over the first 50 bounces (point and disk)."""
    radius = radius_fraction * world.diameter
    kin, phys = _pair(world, seed=WORLDS.index(world), radius=radius)
    assert kin.drive_to_contact() == phys.drive_to_contact()
    angles = np.random.default_rng(1).uniform(0.1, 2 * np.pi - 0.1, 50)
    edges_k, edges_p = [], []
    for phi in angles:
        assert kin.bounce(phi) == phys.bounce(phi)
        edges_k.append(int(kin.state.contact_edge[0]))
        edges_p.append(int(phys.state.contact_edge[0]))
        np.testing.assert_allclose(phys.state.position, kin.state.position, rtol=0, atol=1e-6)
        np.testing.assert_allclose(
            phys.state.contact_normal, kin.state.contact_normal, rtol=0, atol=1e-9
        )
    assert edges_p == edges_k
    assert len(set(edges_k)) > 2  # the run visits several walls
    for field in ("clock", "bumps", "blocked"):
        np.testing.assert_array_equal(getattr(phys.state, field), getattr(kin.state, field))
    assert phys.state.ticks == kin.state.ticks
    np.testing.assert_allclose(phys.state.odometer, kin.state.odometer, rtol=1e-9)


def test_tick_mode_and_corner_bumps_agree():
    """Tick stepping into a corner: the same bump string and clocks as the kinematic backend."""
    strings = []
    for backend in ("kinematic", "pymunk"):
        dyn = BounceDynamics(SQUARE, backend=backend, physics="ideal")
        dyn.reset(np.random.default_rng(0), position=[[9.5, 9.5]], heading=[np.radians(45)])
        strings.append("".join(str(int(dyn.tick(np.radians(90))[0])) for _ in range(40)))
        strings.append((dyn.state.clock.tolist(), dyn.state.position.round(9).tolist()))
    assert strings[0] == strings[2] and strings[1] == strings[3]
    assert strings[0].startswith("011")


def test_disk_passing_a_reflex_corner_is_stopped():
    """A disk whose centre line misses both edges of a hole corner still touches the corner.

    (A plain radius segment query of pymunk culls by the centre line and misses this contact.)
    """
    world = World([(-5, -5), (10, -5), (10, 5), (-5, 5)], [[(0, 0), (0, 2), (2, 2), (2, 0)]])
    for backend in ("kinematic", "pymunk"):
        dyn = BounceDynamics(world, backend=backend, physics="ideal", radius=0.3)
        state = dyn.reset(np.random.default_rng(0), position=[[-3, -0.1]], heading=[0.0])
        dyn.drive_to_contact()
        assert state.contact_edge[0] == 4  # the hole's vertex (0, 0), which starts edge 4
        np.testing.assert_allclose(state.position[0], [-np.sqrt(0.3**2 - 0.1**2), -0.1])
        np.testing.assert_allclose(np.hypot(*state.contact_normal[0]), 1.0)


@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_never_leaves_the_free_space(radius):
    dyn = BounceDynamics(HOLED, backend="pymunk", physics="ideal", radius=radius)
    state = dyn.reset(np.random.default_rng(3))
    dyn.drive_to_contact()
    rng = np.random.default_rng(4)
    positions = np.empty((10_000, 2))
    for k, phi in enumerate(rng.uniform(0.05, 2 * np.pi - 0.05, len(positions))):
        dyn.bounce(phi)
        positions[k] = state.position[0]
    assert HOLED.contains(positions, radius).all()
    # every stop is a real contact: at distance radius from the boundary
    np.testing.assert_allclose(HOLED.boundary_distance(positions), radius, atol=1e-7)


def _run(dyn, rng, n):
    out = []
    for _ in range(n):
        ticks = dyn.bounce(rng.uniform(0.1, 6.2, dyn.n_robots))
        out.append((ticks, dyn.state.position.copy(), dyn.state.contact_edge.copy()))
    return out


def _same(run_a, run_b):
    for (ta, pa, ea), (tb, pb, eb) in zip(run_a, run_b, strict=True):
        assert ta == tb
        np.testing.assert_array_equal(pa, pb)
        np.testing.assert_array_equal(ea, eb)


@pytest.mark.parametrize("n_robots", [1, 4])
def test_deterministic_and_pickle_round_trip_continues_identically(n_robots):
    kwargs = {"backend": "pymunk", "physics": "ideal", "radius": 0.5, "robot_collisions": "bounce",
              "noise": {"type": "reliable", "r": 0.7, "eps": 0.3}}
    a = BounceDynamics(HOLED, n_robots, **kwargs)
    b = BounceDynamics(HOLED, n_robots, **kwargs)
    a.reset(np.random.default_rng(11))
    b.reset(np.random.default_rng(11))
    ra, rb = np.random.default_rng(0), np.random.default_rng(0)
    _same(_run(a, ra, 300), _run(b, rb, 300))
    c = pickle.loads(pickle.dumps(a))
    assert c.backend._space is None  # rebuilt on demand
    rc = pickle.loads(pickle.dumps(ra))
    _same(_run(a, ra, 300), _run(c, rc, 300))


def test_multi_robot_never_overlap_and_agree_with_kinematic():
    m, radius = 5, 0.5
    runs = {}
    for backend in ("kinematic", "pymunk"):
        dyn = BounceDynamics(HOLED, m, backend=backend, physics="ideal", radius=radius, robot_collisions="bounce")
        state = dyn.reset(np.random.default_rng(21))
        rng = np.random.default_rng(22)
        robot_contacts, history = 0, []
        for _ in range(2000):
            dyn.bounce(rng.uniform(0.1, 6.2, m))
            diff = state.position[:, None] - state.position[None]
            dist = np.hypot(diff[..., 0], diff[..., 1]) + np.eye(m) * 99
            assert dist.min() >= 2 * radius - 1e-6
            assert HOLED.contains(state.position, radius).all()
            robot_contacts += int((state.contact_robot >= 0).sum())
            history.append((state.ticks, state.contact_edge.tolist(), state.contact_robot.tolist()))
        assert robot_contacts > 0
        runs[backend] = (history[:300], state.bumps.copy())
    # the discrete history agrees with the exact backend for the first few hundred bounces
    assert runs["pymunk"][0] == runs["kinematic"][0]


def test_head_on_robots_both_blocked():
    dyn = BounceDynamics(SQUARE, 2, backend="pymunk", physics="ideal", radius=0.5, robot_collisions="bounce")
    state = dyn.reset(np.random.default_rng(0), position=[[2, 4], [8, 4]], heading=[0, np.pi])
    assert dyn.drive_to_contact() == 3
    assert state.blocked.all() and state.contact_robot.tolist() == [1, 0]
    np.testing.assert_allclose(state.position, [[4.5, 4], [5.5, 4]])
    np.testing.assert_allclose(state.contact_normal, [[-1, 0], [1, 0]])


def test_one_space_per_backend_and_callbacks_are_the_sensor():
    dyn = BounceDynamics(SQUARE, backend="pymunk", physics="ideal")
    dyn.reset(np.random.default_rng(0), position=[[5, 5]], heading=[0.0])
    first = dyn.backend._space
    dyn.reset(np.random.default_rng(0), position=[[5, 5]], heading=[0.0])
    assert dyn.backend._space is first  # reused: a dropped Space is cyclic garbage
    # silence the engine's callback: the predicted contact is then refused, not trusted
    dyn.backend._on_touch = lambda arbiter, space, data: None
    dyn.backend._build_space()
    with pytest.raises(RuntimeError, match="pymunk reported no contact between robot 0 and edge"):
        dyn.drive_to_contact()
    pair = BounceDynamics(SQUARE, 2, backend="pymunk", physics="ideal", radius=0.5, robot_collisions="bounce")
    pair.reset(np.random.default_rng(0), position=[[2, 4], [8, 4]], heading=[0, np.pi])
    pair.backend._on_touch = lambda arbiter, space, data: None
    pair.backend._build_space()
    with pytest.raises(RuntimeError, match="reached another robot"):
        pair.drive_to_contact()


def test_bad_start_positions_raise():
    backend = PymunkBackend(SQUARE, 2, 1.0, 1.0, "bounce")
    dyn = BounceDynamics(SQUARE, 2, backend="pymunk", physics="ideal", radius=1.0, robot_collisions="bounce")
    assert backend.name == dyn.backend.name == "pymunk"
    with pytest.raises(ConfigError, match="not in the free space"):
        dyn.reset(np.random.default_rng(0), position=[[0.5, 4], [5, 4]])
    with pytest.raises(ConfigError, match="overlap"):
        dyn.reset(np.random.default_rng(0), position=[[4, 4], [5, 4]])


def test_contact_due_at_once_is_sensed_without_moving():
    """A robot touching (and facing) another robot but not marked blocked: a zero-length event.

    pymunk ignores ``step(0)``, so the backend takes a step too short to move anything; the
    callback must still report the contact, exactly as the kinematic backend blocks the robot.
    """
    results = []
    for backend in ("kinematic", "pymunk"):
        dyn = BounceDynamics(SQUARE, 2, backend=backend, physics="ideal", radius=0.5, robot_collisions="bounce")
        state = dyn.reset(
            np.random.default_rng(0), position=[[4.5, 4], [5.5, 4]], heading=[0, np.pi / 2]
        )
        assert state.blocked.tolist() == [True, False]
        state.blocked[0] = False  # changed from outside
        assert dyn.backend.drive(state, np.inf, until_first_block=True) == 0
        assert state.blocked.tolist() == [True, False] and state.contact_robot[0] == 1
        np.testing.assert_array_equal(state.position, [[4.5, 4], [5.5, 4]])
        results.append(state.contact_normal.copy())
    np.testing.assert_array_equal(results[0][0], results[1][0])


def test_one_physics_step_per_bounce():
    dyn = BounceDynamics(HOLED, backend="pymunk", physics="ideal", radius=0.3)
    dyn.reset(np.random.default_rng(5))
    dyn.drive_to_contact()
    space = dyn.backend._space
    steps = []
    step = space.step
    space.step = lambda dt: (steps.append(dt), step(dt))[1]
    drives = 0
    for phi in np.random.default_rng(6).uniform(0.1, 6.2, 200):
        drives += dyn.bounce(phi) > 1  # a turn that still faces the wall drives nowhere
    assert drives > 50
    assert len(steps) == drives and min(steps) > 0


def test_no_escape_at_grid_vertices_with_45_degree_headings():
    """Cell centres and multiples of 45°: rays run exactly through reflex vertices."""
    free = np.argwhere(GRID.occupancy(1.0))
    xmin, ymin = GRID.bounds[:2]
    rng = np.random.default_rng(9)
    for radius in (0.0, 0.25):
        for r, c in free[::3]:
            dyn = BounceDynamics(GRID, backend="pymunk", physics="ideal", radius=radius)
            start = [[xmin + c + 0.5, ymin + r + 0.5]]
            state = dyn.reset(rng, position=start, heading=[np.radians(45)])
            for phi in rng.choice(np.radians([45, 90, 135, 180, 225, 270]), 300):
                dyn.tick(phi)
                assert GRID.contains(state.position, radius)[0]


def test_reused_space_gives_the_same_episodes_as_a_new_one():
    """The Space is kept across resets; episodes must not depend on what happened before."""
    def episode(dyn, seed):
        dyn.reset(np.random.default_rng(seed))
        dyn.drive_to_contact()
        angles = np.random.default_rng(seed + 100).uniform(0.2, 6.0, (150, 3))
        for row in angles:
            dyn.bounce(row)
        return dyn.state.position.copy(), dyn.state.clock.copy(), dyn.state.ticks

    kwargs = dict(backend="pymunk", physics="ideal", radius=0.4, robot_collisions="bounce")
    veteran = BounceDynamics(HOLED, 3, **kwargs)
    for seed in range(5):
        episode(veteran, seed)  # leaves robots resting, filters switched, contacts recorded
    fresh = BounceDynamics(HOLED, 3, **kwargs)
    a, b = episode(veteran, 42), episode(fresh, 42)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert a[2] == b[2]


@pytest.mark.parametrize("backend", ["kinematic", "pymunk"])
@pytest.mark.parametrize("world", [HOLED, GRID, worlds.get("two_rooms")], ids=lambda w: w.name)
@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_lone_robot_drive_is_the_event_loop_bit_for_bit(backend, world, radius):
    """A lone robot's scalar `drive` against the general event loop, bit for bit: bounces,
    ticks and drive windows of whole, fractional and zero ticks, with and without stopping at
    the first block, on a step length that makes tick rounding matter."""
    lean, loop = (BounceDynamics(world, backend=backend, physics="ideal", radius=radius, step_length=0.7)
                  for _ in range(2))
    loop.backend._drive_lone = loop.backend._drive_events  # route every drive to the loop
    for dyn in (lean, loop):
        dyn.reset(np.random.default_rng(4))
    rng = np.random.default_rng(5)
    for _ in range(600):
        kind, phi = rng.integers(4), rng.uniform(0.1, 2 * np.pi - 0.1)
        ticks = rng.choice([0.0, 1.0, 2.5, 4.0, np.inf])
        until = bool(rng.integers(2)) or ticks == np.inf
        results = []
        for dyn in (lean, loop):
            if kind == 0:
                results.append(dyn.bounce(phi))
            elif kind == 1:
                results.append(dyn.tick(phi).tolist())
            else:
                if dyn.state.blocked[0]:
                    dyn.turn(np.array([phi]))
                results.append(dyn.backend.drive(dyn.state, ticks, until))
        assert results[0] == results[1]
        a, b = lean.state, loop.state
        for name in ("position", "heading", "blocked", "clock", "bumps", "contact_edge",
                     "contact_robot", "contact_normal", "odometer"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
        assert a.ticks == b.ticks
