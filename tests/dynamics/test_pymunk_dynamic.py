"""``physics="dynamic"``: rigid-body robots with motors, a bumper and turning time.

The checks of issue 23: (a) in the limit of an ideal robot the model is the exact kinematic
one; (b) the engine conserves momentum and never creates energy, and a frictionless wall keeps
a sliding robot's tangential speed; (d) same seed, same trajectory — also after pickling mid-run,
and after a reset of a used space; plus the controller's behaviour (turns take clock ticks,
bumpers, pushing, sliding) and its options. Escapes over the nasty worlds: tests/adversarial/
test_dynamic_worlds.py; the environments' API tests run on it in tests/envs.
"""

import math
import pickle

import numpy as np
import pytest

from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.backends.dynamic_engine import WALL, DynamicEngine
from bounce_gym.dynamics.backends.pymunk_dynamic import DEPTH, PHASES, DynamicBackend
from bounce_gym.dynamics.platform import PLATFORM_RADIUS, PhysicsParams, physics_params
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

SQUARE = World([(0, 0), (10, 0), (10, 10), (0, 10)])
#: the limit of an ideal robot: instant speed changes and turns, no friction, no rebound
IDEAL = {"max_acceleration": math.inf, "max_speed": math.inf, "turn_rate": math.inf,
         "friction": 0.0, "restitution": 0.0, "control_period": 1e-9}
LIMIT_WORLDS = ["grid_10x10", "grid_15x15", "grid_20x12", "lab_complex", "lab_fig1",
                "lab_localization_a", "lab_navigation", "two_rooms", "l_shape", "heptagon"]
#: Measured over the 10 worlds x 60 bounces: equal ticks and clocks at every bounce, headings
#: within 3.2e-12 rad, positions within 1.9e-6 world units (9e-8 of the map). Each contact
#: differs by half the contact depth (`DEPTH` / 2 = 1e-7 radii, 1.7e-8 units); the billiard
#: then stretches such offsets by 1/sin of the angle at every glancing bounce.
LIMIT_TOL = 1e-5


def dynamic(world=SQUARE, n_robots=1, radius=0.17, **kwargs) -> BounceDynamics:
    params = kwargs.pop("params", None)
    return BounceDynamics(world, n_robots, backend="pymunk", radius=radius, physics="dynamic",
                          physics_params=params, **kwargs)


# -- (a) the limit ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", LIMIT_WORLDS)
def test_ideal_limit_is_the_kinematic_trajectory(name):
    """Infinite acceleration and turn rate, restitution 0, friction 0, a control period of
    1e-9 s: the same bump ticks and clocks as the exact backend, headings within 1e-9 rad and
    positions within `LIMIT_TOL` world units after each of 60 bounces."""
    world = worlds.get(name)
    rng = np.random.default_rng(LIMIT_WORLDS.index(name))
    start = world.sample_free(rng, 1, PLATFORM_RADIUS), rng.uniform(0, 2 * np.pi, 1)
    angles = np.random.default_rng(1).uniform(0.3, 2 * np.pi - 0.3, 60)
    runs = []
    for model in ("kinematic", "dynamic"):
        dyn = (dynamic(world, params=IDEAL) if model == "dynamic" else
               BounceDynamics(world, radius=PLATFORM_RADIUS))
        state = dyn.reset(np.random.default_rng(0), *start)
        history = [(dyn.drive_to_contact(), int(state.clock[0]), state.position[0].copy(),
                    float(state.heading[0]))]
        for phi in angles:
            history.append((dyn.bounce(phi), int(state.clock[0]), state.position[0].copy(),
                            float(state.heading[0])))
        runs.append(history)
    for (ticks, clock, position, heading), (ticks_d, clock_d, position_d, heading_d) in zip(
            *runs, strict=True):
        assert (ticks_d, clock_d) == (ticks, clock)
        assert np.max(np.abs(position_d - position)) < LIMIT_TOL
        assert abs(math.remainder(heading_d - heading, 2 * math.pi)) < 1e-9


# -- (b) the engine's physics -------------------------------------------------------------------
def _engine(n, restitution, friction, world=None) -> DynamicEngine:
    world = world or World([(-100, -100), (100, -100), (100, 100), (-100, 100)])
    return DynamicEngine(world, n, 0.17, 3.6, restitution, friction, 10, collide=True)


def _momentum_energy(engine):
    bodies = engine.read()
    p = sum(np.array([b[3], b[4]]) for b in bodies) * engine.mass
    e = sum(0.5 * engine.mass * (b[3] ** 2 + b[4] ** 2) + 0.5 * engine.moment * b[5] ** 2
            for b in bodies)
    return p, e


@pytest.mark.parametrize("offset", [0.0, 0.1, 0.25])
def test_free_collision_with_restitution_1_conserves_momentum_and_energy(offset):
    """Two robots, no motors (the engine alone), head-on or off-centre, restitution 1."""
    engine = _engine(2, 1.0, 0.0)
    engine.set_bodies(np.array([[-1.0, 0.0], [1.0, offset]]), np.zeros(2),
                      np.array([[0.3, 0.0], [-0.2, 0.0]]), np.array([0.0, 1.5]))
    p0, e0 = _momentum_energy(engine)
    touched = False
    for _ in range(6000):
        touched |= bool(engine.step(1e-3))
    p1, e1 = _momentum_energy(engine)
    assert touched
    np.testing.assert_allclose(p1, p0, rtol=0, atol=1e-12)
    assert e1 == pytest.approx(e0, rel=1e-9)


def test_sliding_along_a_frictionless_wall_keeps_the_tangential_speed():
    engine = _engine(1, 0.0, 0.0, world=SQUARE)
    engine.set_bodies(np.array([[5.0, 0.3]]), np.zeros(1), np.array([[0.2, -0.1]]), np.zeros(1))
    contacts = 0
    for _ in range(200):
        contacts += sum(c[1] == WALL for c in engine.step(0.01))
    _, _, _, vx, vy, _ = engine.read()[0]
    assert contacts > 0
    assert vx == pytest.approx(0.2, abs=1e-12) and abs(vy) < 1e-12  # slides on at 0.2


def test_energy_never_grows():
    """Twelve robots, no motors, random restitution and friction, in a room with a hole:
    the kinetic energy (with rotation) never rises from one step to the next."""
    rng = np.random.default_rng(5)
    world = worlds.get("lab_fig1")
    for restitution in (0.0, 0.5, 1.0):
        engine = DynamicEngine(world, 12, 0.2, 3.6, restitution, float(rng.uniform(0, 1)), 10,
                               collide=True)
        spots = world.sample_free(rng, 40, 0.2)
        chosen = [spots[0]]
        for p in spots[1:]:
            if len(chosen) < 12 and min(np.hypot(*(p - q)) for q in chosen) > 0.45:
                chosen.append(p)
        engine.set_bodies(np.array(chosen), np.zeros(12), rng.uniform(-0.3, 0.3, (12, 2)),
                          rng.uniform(-2, 2, 12))
        _, energy = _momentum_energy(engine)
        for _ in range(1500):
            engine.step(0.004)
            _, after = _momentum_energy(engine)
            assert after <= energy * (1 + 1e-12) + 1e-15
            energy = after


# -- (d) determinism ----------------------------------------------------------------------------
def _crowd(seed=3, n=6):
    dyn = dynamic(worlds.get("grid_10x10"), n, robot_collisions="bounce",
                  noise={"type": "reliable", "r": 0.7, "eps_deg": 20})
    dyn.reset(np.random.default_rng(seed))
    dyn.drive_to_contact()
    return dyn


def _trace(dyn, n_steps, seed=9):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n_steps):
        ticks = dyn.bounce(rng.uniform(0.3, 6.0, dyn.n_robots))
        s = dyn.state
        out.append((ticks, s.position.tobytes(), s.heading.tobytes(), s.clock.tobytes(),
                    s.bumps.tobytes(), s.contact_robot.tobytes()))
    return out


def test_same_seed_same_crowd_trajectory_and_a_reused_space_repeats_it():
    a, b = _crowd(), _crowd()
    first = _trace(a, 60)
    assert first == _trace(b, 60)
    assert any(t[-1] != np.full(6, -1).tobytes() for t in first)  # robots bumped robots
    a.reset(np.random.default_rng(3))  # the same space, its ids and trees back to canonical
    a.drive_to_contact()
    assert _trace(a, 60) == first


@pytest.mark.parametrize("n_robots", [1, 6])
def test_pickling_mid_run_continues_bit_for_bit(n_robots):
    """Pickling drops the pymunk space; the rebuilt one (same shape ids, same trees, no warm
    starting) continues exactly — colliding crowds included."""
    dyn = _crowd(n=n_robots) if n_robots > 1 else dynamic(worlds.get("two_rooms"))
    if n_robots == 1:
        dyn.reset(np.random.default_rng(4))
        dyn.drive_to_contact()
    _trace(dyn, 15, seed=1)
    twin = pickle.loads(pickle.dumps(dyn))
    assert twin.backend.engine._space is None  # really rebuilt
    assert _trace(twin, 60) == _trace(dyn, 60)


def test_warm_starting_is_off():
    """A robot resting on a wall after an impact in a short step is not thrown off by the next,
    longer step (Chipmunk would scale the impact's impulse by the ratio of the steps)."""
    engine = _engine(1, 0.0, 0.3, world=SQUARE)
    engine.set_bodies(np.array([[5.0, 0.17 + 1e-9]]), np.zeros(1), np.array([[0.0, -0.25]]),
                      np.zeros(1))
    engine.step(1e-6)  # impact: the wall stops the robot
    for _ in range(5):
        engine.step(0.5)
    x, y, _, vx, vy, _ = engine.read()[0]
    assert abs(vy) < 1e-12 and abs(y - 0.17) < 1e-6


# -- the controller -----------------------------------------------------------------------------
def test_a_bounce_turns_in_place_and_the_turn_takes_ticks():
    """A slow turn rate: the 135° turn lasts several ticks, all on the clock; the robot turns
    in place, then drives on at the cruise speed."""
    params = {"turn_rate": 10.0, "max_acceleration": 0.5}
    dyn = dynamic(params=params, step_length=0.25)  # a tick of one second
    state = dyn.reset(np.random.default_rng(0), np.array([[5.0, 5.0]]), np.array([0.0]))
    dyn.drive_to_contact()
    at_wall = state.position.copy()
    assert state.blocked[0] and state.contact_edge[0] == 1 and at_wall[0, 0] > 9.8
    ticks = []
    dyn.backend.begin_turns(state, np.array([0]), np.array([math.radians(135)]))
    state.clock[0] = 0
    for _ in range(20):
        ticks.append(dyn.backend.drive(state, 1, until_first_block=False))
        if PHASES[dyn.backend.phase[0]] == "drive":
            break
    turn_ticks = len(ticks)
    assert turn_ticks >= math.ceil(135 / 10)  # 13.5 s at 10°/s
    np.testing.assert_allclose(state.position, at_wall, atol=1e-9)  # turned in place
    assert state.heading[0] == pytest.approx(math.radians(135), abs=1e-9)
    assert state.clock[0] == turn_ticks - 1  # every turning tick counts but the bump tick


def test_clock_counts_turning_ticks_after_the_bump_tick():
    dyn = dynamic(params={"turn_rate": 20.0}, step_length=0.25)
    state = dyn.reset(np.random.default_rng(0), np.array([[5.0, 5.0]]), np.array([0.0]))
    dyn.drive_to_contact()
    ticks = dyn.bounce(math.radians(180))  # 9 s of turning, then back across the square
    assert state.bumps[0] == 1 and state.blocked[0]
    assert state.clock[0] == ticks - 1  # every tick but the bump tick
    assert ticks > 9 + 36  # the turn, then 9.6 units at 0.25 units/s


def test_turn_command_takes_time_and_others_hold():
    dyn = dynamic(worlds.get("grid_10x10"), 3, robot_collisions="bounce",
                  params={"turn_rate": 45.0}, step_length=0.25)  # ticks of one second
    state = dyn.reset(np.random.default_rng(2))
    dyn.tick(np.full(3, 1.0))
    dyn.tick(np.full(3, 1.0))
    heading, ticks, clock, bumps = (state.heading.copy(), state.ticks, state.clock.copy(),
                                    state.bumps.copy())
    dyn.turn(np.array([math.radians(90), np.nan, np.nan]))
    elapsed = state.ticks - ticks
    assert elapsed >= 2  # 90° at 45°/s: two seconds
    assert np.array_equal(state.clock, clock + elapsed)
    assert math.remainder(state.heading[0] - heading[0] - math.radians(90), 2 * math.pi) \
        == pytest.approx(0.0, abs=1e-9)
    assert np.array_equal(state.bumps, bumps)  # a command is no bump


def test_head_on_robots_both_bump():
    dyn = dynamic(SQUARE, 2, robot_collisions="bounce")
    state = dyn.reset(np.random.default_rng(0), np.array([[3.0, 5.0], [7.0, 5.0]]),
                      np.array([0.0, math.pi]))
    dyn.drive_to_contact()
    for _ in range(3):
        if state.blocked.all():
            break
        dyn.backend.drive(state, 1, until_first_block=False)
    assert state.blocked.all()
    assert list(state.contact_robot) == [1, 0]
    np.testing.assert_allclose(state.contact_normal, [[-1, 0], [1, 0]], atol=1e-6)
    gap = np.hypot(*(state.position[0] - state.position[1]))
    assert 2 * 0.17 - 2 * DEPTH * 0.17 <= gap <= 2 * 0.17 + 1e-9


def _glancing_slide(params: dict) -> float:
    """Hit the floor 60° from its normal: how far along it the robot slides while braking."""
    dyn = dynamic(params=params)
    heading = math.radians(-30)
    state = dyn.reset(np.random.default_rng(0), np.array([[2.0, 1.0]]), np.array([heading]))
    dyn.drive_to_contact()
    assert state.blocked[0] and state.contact_edge[0] == 0
    assert state.position[0, 1] == pytest.approx(0.17, abs=1e-6)  # on the floor
    return state.position[0, 0] - (2.0 + (1.0 - 0.17) / math.tan(-heading))


def test_a_glancing_bump_slides_along_the_wall_while_braking():
    """The wall stops the normal motion at once; the tangential one slides on while the motors
    brake at max_acceleration, over about v_t² / 2a without friction; friction shortens it."""
    tangential = 0.25 * math.sin(math.radians(60))
    free = _glancing_slide({"friction": 0.0, "max_acceleration": 0.25})
    assert free == pytest.approx(tangential ** 2 / (2 * 0.25), rel=0.3)
    rough = _glancing_slide({"friction": 1.0, "max_acceleration": 0.25})
    assert 0.0 <= rough < 0.5 * free


def test_a_narrow_bumper_misses_glancing_contacts():
    """With a 60° bumper, a floor met 70° off the heading is outside the arc: the robot slides
    along it without bumping, until the wall ahead meets its bumper."""
    dyn = dynamic(params={"bumper_arc": 60.0, "friction": 0.0})
    state = dyn.reset(np.random.default_rng(0), np.array([[2.0, 2.0]]),
                      np.array([math.radians(-20)]))
    dyn.drive_to_contact()
    assert state.contact_edge[0] == 1  # the right wall (x = 10), not the floor it slid along
    assert state.position[0, 1] == pytest.approx(0.17, abs=1e-5)
    assert state.position[0, 0] == pytest.approx(10 - 0.17, abs=1e-5)


def test_renderer_hooks():
    dyn = dynamic()
    dyn.reset(np.random.default_rng(0), np.array([[5.0, 5.0]]), np.array([0.0]))
    assert PHASES[dyn.backend.phase[0]] == "drive"
    dyn.drive_to_contact()
    assert PHASES[dyn.backend.phase[0]] == "blocked" and dyn.backend.bumper_pressed[0]


# -- options ------------------------------------------------------------------------------------
def test_defaults_are_a_create_2():
    p = PhysicsParams()
    assert (p.mass, p.wheel_base, p.max_speed, p.cruise_speed) == (3.6, 0.235, 0.5, 0.25)
    assert p.max_turn_rate == pytest.approx(4.255, abs=1e-3)
    assert math.radians(p.turn_rate) == pytest.approx(2 * 0.25 / 0.235)
    assert p.bumper_arc == 180.0 and p.restitution == 0.0
    dyn = dynamic(radius=PLATFORM_RADIUS)
    assert isinstance(dyn.backend, DynamicBackend)
    assert dyn.backend.tick_seconds == pytest.approx(4.0)  # 1 unit at 0.25 m/s


@pytest.mark.parametrize(("params", "field"), [
    ({"mass": 0}, "mass"),
    ({"cruise_speed": 0.6}, "cruise_speed"),
    ({"turn_rate": 300}, "turn_rate"),
    ({"restitution": 1.5}, "restitution"),
    ({"friction": -1}, "friction"),
    ({"bumper_arc": 400}, "bumper_arc"),
    ({"control_period": math.inf}, "control_period"),
    ({"iterations": 0}, "iterations"),
    ({"stall_fraction": 0}, "stall_fraction"),
    ({"stall_fraction": 1.5}, "stall_fraction"),
    ({"stall_time": math.inf}, "stall_time"),
    ({"max_acceleration": "fast"}, "max_acceleration"),
    ({"wheels": 2}, "unknown parameters"),
])
def test_bad_parameters_are_one_line_config_errors(params, field):
    with pytest.raises(ConfigError, match=field) as err:
        physics_params(params)
    assert "\n" not in str(err.value)


def test_point_robots_and_other_backends_refuse_dynamic():
    with pytest.raises(ConfigError, match="robot_radius"):
        dynamic(radius=0.0)
    with pytest.raises(ConfigError, match="physics='dynamic' needs backend='pymunk'"):
        BounceDynamics(SQUARE, physics="dynamic")
    with pytest.raises(ConfigError, match="physics_params"):
        BounceDynamics(SQUARE, backend="pymunk", physics="ideal", physics_params={"mass": 1})
    with pytest.raises(ConfigError, match="physics"):
        BounceDynamics(SQUARE, backend="pymunk", physics="rigid")
    with pytest.raises(ConfigError, match="does not drive robots independently"):
        dynamic().bounce_each(1.0)
