"""Tick/bounce semantics of `BounceDynamics` on the exact kinematic backend."""

import contextlib
import io
import math
import pickle
import subprocess
import sys

import numpy as np
import pytest

from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

BOX = World([(0, 0), (10, 0), (10, 8), (0, 8)], name="box")
ROOM = World(
    [(0, 0), (20, 0), (20, 12), (11, 12), (11, 16), (0, 16)],
    [[(3, 3), (6, 3), (5, 7)], [(12, 2), (16, 2), (16, 5), (12, 5)]],
    name="room",
)
deg = np.radians


def test_rectangle_loop_with_relative_90():
    """Point robot from (1.5, 0.5) heading East, φ = 90°: the CCW wall loop, ticks = ceil(distance)."""
    dyn = BounceDynamics(BOX)
    state = dyn.reset(np.random.default_rng(0), position=[[1.5, 0.5]], heading=[0.0])
    assert dyn.drive_to_contact() == 9  # 8.5 units
    np.testing.assert_allclose(state.position, [[10.0, 0.5]], atol=1e-12)
    assert state.blocked[0] and state.clock[0] == 9
    expected = [((10, 8), 90, 8, 2), ((0, 8), 180, 10, 3), ((0, 0), 270, 8, 0), ((10, 0), 0, 10, 1)]
    for corner, heading, clock, edge in expected:
        ticks = dyn.bounce(deg(90))
        assert ticks == 1 + clock
        np.testing.assert_allclose(state.position[0], corner, atol=1e-12)
        assert np.degrees(state.heading[0]) == pytest.approx(heading)
        assert state.clock[0] == clock and state.contact_edge[0] == edge
    assert state.bumps[0] == 4 and state.ticks == 9 + 9 + 11 + 9 + 11


def test_corner_gives_consecutive_bumps_in_tick_mode():
    """Heading into a corner at 45° with φ = 90°: the first turn still faces a wall (thesis
    §2.3.1)."""
    dyn = BounceDynamics(BOX)
    dyn.reset(np.random.default_rng(0), position=[[9.5, 7.5]], heading=[deg(45)])
    bumps = "".join(str(int(dyn.tick(deg(90))[0])) for _ in range(12))
    assert bumps == "011000000000"
    assert np.degrees(dyn.state.heading[0]) == pytest.approx(225)
    assert dyn.state.clock[0] == 9


def test_bounce_mode_is_tick_mode_that_stops_when_a_robot_needs_an_angle():
    rng = np.random.default_rng(5)
    angles = rng.uniform(deg(10), deg(350), size=(300, 3))
    a = BounceDynamics(ROOM, 3, radius=0.4, robot_collisions="bounce")
    b = BounceDynamics(ROOM, 3, radius=0.4, robot_collisions="bounce")
    sa = a.reset(np.random.default_rng(1))
    sb = b.reset(np.random.default_rng(1))
    a.drive_to_contact()
    while not sb.blocked.any():
        b.tick(deg(90))
    for row in angles:
        a.bounce(row)
        b.tick(row)
        while not sb.blocked.any():
            b.tick(deg(90))  # nobody is blocked, so the angle is unused
        # unit steps and one long drive round differently; the discrete history is identical
        assert sa.ticks == sb.ticks
        np.testing.assert_allclose(sa.position, sb.position, atol=1e-9)
        np.testing.assert_array_equal(sa.clock, sb.clock)
        np.testing.assert_array_equal(sa.bumps, sb.bumps)


def test_single_robot_fast_path_equals_the_general_integrator():
    rng = np.random.default_rng(6)
    angles = rng.uniform(0.1, 6.2, 500)
    fast = BounceDynamics(ROOM, radius=0.3)
    slow = BounceDynamics(ROOM, radius=0.3)
    slow._scalar_path = False  # force the vectorised event loop
    for dyn in (fast, slow):
        dyn.reset(np.random.default_rng(2))
        dyn.drive_to_contact()
    for a in angles:
        assert fast.bounce(a) == slow.bounce(a)
    for field in ("position", "heading", "clock", "bumps", "contact_edge", "odometer"):
        np.testing.assert_array_equal(getattr(fast.state, field), getattr(slow.state, field))
    assert fast.state.ticks == slow.state.ticks


@pytest.mark.parametrize("rule", ["relative", "fixed", "specular", "monotonic", "nilles_relative"])
@pytest.mark.parametrize("radius", [0.0, 0.35])
def test_no_escape_and_exact_contacts(rule, radius):
    rng = np.random.default_rng(7)
    dyn = BounceDynamics(ROOM, rule=rule, radius=radius, noise={"type": "interval", "lo": -0.2, "hi": 0.2})
    state = dyn.reset(np.random.default_rng(3))
    dyn.drive_to_contact()
    low, high = (0.3, 2.8) if rule != "relative" else (0.1, 6.2)
    for _ in range(3000):
        dyn.bounce(rng.uniform(low, high))
        assert ROOM.contains(state.position, radius)[0]
        if state.contact_robot[0] < 0 and not state.blocked[0]:
            continue
        # the robot touches the wall it reports
        assert ROOM.boundary_distance(state.position)[0] == pytest.approx(radius, abs=1e-7)


def test_determinism_same_seed_and_after_pickling():
    def run(dyn, rng, n):
        return [(dyn.bounce(rng.uniform(0.1, 6.2, 4)), dyn.state.position.copy()) for _ in range(n)]

    kwargs = dict(radius=0.5, robot_collisions="bounce", noise={"type": "reliable", "r": 0.7, "eps": 0.3})
    a = BounceDynamics(ROOM, 4, **kwargs)
    b = BounceDynamics(ROOM, 4, **kwargs)
    a.reset(np.random.default_rng(11)), b.reset(np.random.default_rng(11))
    ra, rb = np.random.default_rng(0), np.random.default_rng(0)
    for (ta, pa), (tb, pb) in zip(run(a, ra, 200), run(b, rb, 200), strict=True):
        assert ta == tb and np.array_equal(pa, pb)
    c = pickle.loads(pickle.dumps(a))
    rc = pickle.loads(pickle.dumps(ra))
    for (ta, pa), (tc, pc) in zip(run(a, ra, 200), run(c, rc, 200), strict=True):
        assert ta == tc and np.array_equal(pa, pc)


def test_robots_never_overlap_and_head_on_robots_both_turn():
    dyn = BounceDynamics(BOX, 2, radius=0.5, robot_collisions="bounce")
    state = dyn.reset(np.random.default_rng(0), position=[[2, 4], [8, 4]], heading=[0, np.pi])
    dyn.drive_to_contact()
    assert state.blocked.all() and state.contact_robot.tolist() == [1, 0]
    np.testing.assert_allclose(state.position, [[4.5, 4], [5.5, 4]])
    np.testing.assert_allclose(state.contact_normal, [[-1, 0], [1, 0]])
    dyn.bounce(deg(90))
    assert state.bumps.tolist() == [1, 1]

    crowd = BounceDynamics(ROOM, 8, radius=0.6, robot_collisions="bounce")
    s = crowd.reset(np.random.default_rng(4))
    rng = np.random.default_rng(5)
    robot_contacts = 0
    for _ in range(1500):
        crowd.bounce(rng.uniform(0.1, 6.2, 8))
        diff = s.position[:, None] - s.position[None]
        dist = np.hypot(diff[..., 0], diff[..., 1]) + np.eye(8) * 99
        assert dist.min() >= 1.2 - 1e-7
        robot_contacts += int((s.contact_robot >= 0).sum())
        assert ROOM.contains(s.position, 0.6).all()
    assert robot_contacts > 0


def test_ignored_collisions_let_robots_pass_and_bounce_each_matches_single_runs():
    many = BounceDynamics(ROOM, 16, robot_collisions="ignore")
    s = many.reset(np.random.default_rng(8))
    start_pos, start_head = s.position.copy(), s.heading.copy()
    many.bounce_each(1.0)  # nobody is blocked yet: just drive to the first contact
    angles = np.random.default_rng(9).uniform(0.1, 6.2, (50, 16))
    for row in angles:
        many.bounce_each(row)
    for i in (0, 7, 15):
        one = BounceDynamics(ROOM)
        one.reset(np.random.default_rng(0), position=start_pos[i : i + 1], heading=start_head[i : i + 1])
        one.drive_to_contact()
        for row in angles:
            one.bounce(row[i])
        np.testing.assert_array_equal(one.state.position[0], s.position[i])
        assert one.state.clock[0] == s.clock[i] and one.state.bumps[0] == s.bumps[i]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(n_robots=0), "n_robots"),
        (dict(radius=-1.0), "robot_radius"),
        (dict(radius=np.nan), "robot_radius"),
        (dict(step_length=0.0), "step_length"),
        (dict(backend="box2d"), "backend: unknown backend 'box2d'"),
        (dict(rule="mirror"), "bounce_rule"),
        (dict(robot_collisions="push"), "robot_collisions"),
        (dict(n_robots=3, robot_collisions="bounce"), "needs robot_radius > 0"),
        (dict(noise={"type": "reliable", "r": 2, "eps": 0.1}), "reliability"),
    ],
)
def test_bad_configuration_raises(kwargs, message):
    n = kwargs.pop("n_robots", 1)
    with pytest.raises(ConfigError, match=message):
        BounceDynamics(BOX, n, **kwargs)


def test_bad_reset_and_step_input_raise():
    dyn = BounceDynamics(BOX, 2, radius=1.0, robot_collisions="bounce")
    with pytest.raises(RuntimeError, match="reset"):
        dyn.bounce([0.5, 0.5])
    with pytest.raises(ConfigError, match="rng"):
        dyn.reset(42)
    with pytest.raises(ConfigError, match="not in the free space"):
        dyn.reset(np.random.default_rng(0), position=[[0.5, 4], [5, 4]])
    with pytest.raises(ConfigError, match="overlap"):
        dyn.reset(np.random.default_rng(0), position=[[4, 4], [5, 4]])
    with pytest.raises(ConfigError, match="start position"):
        dyn.reset(np.random.default_rng(0), position=[[4, 4]])
    dyn.reset(np.random.default_rng(0))
    with pytest.raises(ConfigError, match="expected 2 angles"):
        dyn.bounce([0.1, 0.2, 0.3])
    with pytest.raises(ConfigError, match="finite"):
        dyn.tick([np.nan, 0.1])
    with pytest.raises(ConfigError, match="independent driving"):
        dyn.bounce_each([1.0, 1.0])


@pytest.mark.parametrize(("rule", "bad"), [("relative", 0.0), ("relative", 4 * np.pi),
                                           ("fixed", 0.0), ("monotonic", np.pi),
                                           ("nilles_relative", -0.2), ("specular", np.nan)])
def test_rule_parameters_are_validated_per_step(rule, bad):
    dyn = BounceDynamics(BOX, rule=rule)
    dyn.reset(np.random.default_rng(0))
    with pytest.raises(ConfigError, match="bounce parameters"):
        dyn.bounce(bad)


def test_noise_is_an_error_on_the_executed_heading():
    """With Interval noise the turn lands in [φ + lo, φ + hi] (relative rule)."""
    dyn = BounceDynamics(BOX, noise={"type": "interval", "lo_deg": -10, "hi_deg": 10})
    state = dyn.reset(np.random.default_rng(0), position=[[5, 4]], heading=[0.0])
    dyn.drive_to_contact()
    turns = []
    for _ in range(200):
        before = state.heading[0]
        if state.blocked[0]:
            dyn.tick(deg(90))
            turns.append(np.degrees((state.heading[0] - before) % (2 * np.pi)))
        else:
            dyn.tick(deg(90))
    assert min(turns) >= 80 - 1e-9 and max(turns) <= 100 + 1e-9 and np.std(turns) > 3


def test_scalar_parameter_for_many_robots_is_validated():
    dyn = BounceDynamics(BOX, 3)
    dyn.reset(np.random.default_rng(0))
    with pytest.raises(ConfigError, match="multiple of 360"):
        dyn.tick(0.0)


_ROLLOUT = """
import hashlib, numpy as np
from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
dyn = BounceDynamics(worlds.get("two_rooms"), 3, backend="{backend}", physics="ideal", radius=0.2,
                     robot_collisions="bounce", noise={{"type": "reliable", "r": 0.8, "eps": 0.1}})
dyn.reset(np.random.default_rng(123))
angles = np.random.default_rng(7).uniform(0.2, 6.0, (300, 3))
for row in angles:
    dyn.bounce(row)
print(hashlib.sha256(dyn.state.position.tobytes() + dyn.state.clock.tobytes()).hexdigest())
"""


@pytest.mark.parametrize("backend", ["kinematic", "pymunk"])
def test_same_seed_same_trajectory_across_processes(backend):
    code = _ROLLOUT.format(backend=backend)
    runs = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           check=True).stdout for _ in range(2)}
    here = io.StringIO()
    with contextlib.redirect_stdout(here):
        exec(code, {})
    assert runs == {here.getvalue()}


@pytest.mark.parametrize("backend", ["kinematic", "pymunk"])
@pytest.mark.parametrize("dx", [0.0, 4e-16, -4e-16])
def test_touching_robot_sliding_past_tangentially_is_no_contact(backend, dx):
    # robot 0 faces robot 1 (touching, radius 0.3) and is blocked; robot 1 drives east,
    # perpendicular to the line of centres: a graze, not a contact (this once stalled the
    # kinematic integrator when rounding made the pair look approaching)
    dyn = BounceDynamics(worlds.get("grid_10x10"), 2, backend=backend, physics="ideal", radius=0.3,
                         robot_collisions="bounce")
    dyn.reset(np.random.default_rng(0), position=[[2.7, 8.7], [2.7 + dx, 9.3]],
              heading=[math.pi / 2, 0.0])
    assert dyn.state.blocked.tolist() == [True, False]
    dyn.tick([math.pi / 2, math.pi / 2])
    np.testing.assert_allclose(dyn.state.position[1], [3.7 + dx, 9.3], atol=1e-9)
    assert dyn.state.bumps.tolist() == [1, 0]


def test_lone_robot_bump_in_plain_floats_equals_the_relative_rule():
    """The single-robot hot path rotates with float arithmetic; it must match the numpy rule
    bit for bit (same trajectories with one robot as with the vectorised path)."""
    from bounce_gym.dynamics.rules import relative

    dyn = BounceDynamics(BOX)
    dyn.reset(np.random.default_rng(0), position=[[5.0, 4.0]], heading=[0.0])
    rng = np.random.default_rng(1)
    for heading, phi in zip(rng.uniform(0, 2 * np.pi, 500), rng.uniform(-20, 20, 500),
                            strict=True):
        dyn.state.heading[0] = heading
        dyn._rotate(dyn._lone, np.array([phi]))
        assert dyn.state.heading[0] == relative(np.array([heading]), None, phi)[0]
