"""The envs' frames show each robot's heading, bumper (pressed or not), the contact it latched and,
under ``physics="dynamic"``, its motion phase: pixels at positions computed from known poses."""

import math
import pickle

import numpy as np
import pytest

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.envs.render.renderer import (
    BUMPER,
    BUMPER_PRESSED,
    CONTACT,
    INK,
    PHASE_COLOURS,
    Bumpers,
    Renderer,
    robot_colour,
)
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

ROOM = World([(0, 0), (10, 0), (10, 5), (0, 5)], name="room")
RADIUS = 0.5
#: the envs draw with a default renderer: its pixel grid
GRID = Renderer(ROOM)
R_PX = round(RADIUS * GRID.scale)
BACKENDS = {"dynamic": {"backend": "pymunk"},
            "ideal": {"backend": "pymunk", "physics": "ideal"},
            "kinematic": {"backend": "kinematic"}}


def at(frame, x, y, offset=(0.0, 0.0)):
    """The colour at world point (x, y), moved by ``offset`` pixels (right, up)."""
    (col, row), = np.rint(GRID.to_pixels(np.array([[x, y]]))).astype(int)
    return tuple(int(v) for v in frame[row - round(offset[1]), col + round(offset[0])])


def polar(frame, centre, radius_px, angle):
    """The colour ``radius_px`` pixels from the world point ``centre`` in direction ``angle``."""
    return at(frame, *centre, (radius_px * math.cos(angle), radius_px * math.sin(angle)))


def single(backend: str, step_mode: str = "bounce", **kwargs) -> BounceEnv:
    env = BounceEnv(world=ROOM, robot_radius=RADIUS, render_mode="rgb_array",
                    step_mode=step_mode, **BACKENDS[backend], **kwargs)
    env.reset(seed=0, options={"start": {"position": [5.0, 2.5], "heading": 0.0}})
    return env


@pytest.mark.parametrize("backend", sorted(BACKENDS))
def test_blocked_robot_shows_heading_pressed_bumper_and_contact(backend):
    """Driven from (5, 2.5) along +x the robot stops against the wall x = 10: its heading line
    points right, its bumper is pressed, and the contact (10, 2.5) is marked; after a 90°
    bounce (relative rule) it stands against the top wall, facing up, touching (9.5, 5)."""
    env = single(backend)
    frame = env.render()
    centre = (10 - RADIUS, 2.5)
    np.testing.assert_allclose(env.robot_state.position[0], centre, atol=1e-6)
    assert at(frame, 10.0, 2.5) == CONTACT
    assert polar(frame, centre, 0.6 * R_PX, 0.0) == INK  # the heading line, inside the disk
    assert polar(frame, centre, 0.6 * R_PX, math.pi) == robot_colour(0)  # not behind
    for side in (-1, 1):  # the bumper band, 60° off the heading, just inside the rim
        assert polar(frame, centre, R_PX - 3, side * math.radians(60)) == BUMPER_PRESSED
    assert polar(frame, centre, R_PX - 3, math.radians(150)) == robot_colour(0)  # the back
    env.step(1)  # Φ = {45°, 90°, 135°}: 90°
    frame = env.render()
    centre = (10 - RADIUS, 5 - RADIUS)
    np.testing.assert_allclose(env.robot_state.position[0], centre, atol=1e-6)
    assert env.robot_state.heading[0] == pytest.approx(math.pi / 2)
    assert at(frame, 10 - RADIUS, 5.0) == CONTACT
    assert polar(frame, centre, 0.6 * R_PX, math.pi / 2) == INK
    assert polar(frame, centre, 0.6 * R_PX, 0.0) == robot_colour(0)
    assert polar(frame, centre, R_PX - 3, math.pi / 2 + math.radians(60)) == BUMPER_PRESSED
    env.close()


@pytest.mark.parametrize("backend", sorted(BACKENDS))
def test_free_robot_has_an_unpressed_bumper_and_no_contact(backend):
    """Before its first tick (tick mode) the robot stands free at (5, 2.5): its bumper is drawn
    unpressed, nothing is marked where it will touch."""
    env = single(backend, step_mode="tick")
    frame = env.render()
    for side in (-1, 1):
        assert polar(frame, (5.0, 2.5), R_PX - 3, side * math.radians(60)) == BUMPER
    assert at(frame, 10.0, 2.5) != CONTACT
    assert not np.any(np.all(frame == CONTACT, axis=2))
    assert polar(frame, (5.0, 2.5), 0.6 * R_PX, 0.0) == INK
    env.close()


def test_dynamic_phase_is_coloured_at_the_centre():
    """physics="dynamic": a driving robot's centre dot is the drive colour, a blocked one's the
    blocked colour (beside the heading line)."""
    env = single("dynamic", step_mode="tick")
    side = (0.0, -0.2 * R_PX)  # below the centre, off the heading line (heading 0)
    assert env.unwrapped.core.dynamics.backend.phase_names() == ["drive"]
    assert at(env.render(), 5.0, 2.5, side) == PHASE_COLOURS["drive"]
    while not env.robot_state.blocked[0]:
        env.step(0)
    assert at(env.render(), *env.robot_state.position[0], side) == PHASE_COLOURS["blocked"]
    env.close()


def test_a_braking_robot_shows_its_latched_contact_before_it_is_blocked():
    """physics="dynamic", ticks of 0.08 s: meeting the wall x = 10 at a glancing angle, the
    bumper fires and the robot brakes, sliding up along the wall. In those ticks it is not
    blocked yet (the state has no contact), but the backend reports the latched contact, which
    is marked on the wall beside the robot, and the centre dot is the brake colour."""
    env = BounceEnv(world=ROOM, robot_radius=RADIUS, render_mode="rgb_array", step_mode="tick",
                    step_length=0.02, backend="pymunk")
    env.reset(seed=0, options={"start": {"position": [9.0, 1.5], "heading": 0.6}})
    backend = env.unwrapped.core.dynamics.backend
    seen = []
    while not env.robot_state.blocked[0]:
        env.step(0)
        seen.append(backend.phase_names()[0])
        if seen[-1] == "brake":
            assert not env.robot_state.blocked[0]
            pressed, normal = backend.bumpers(env.robot_state)
            np.testing.assert_allclose(normal[0], [-1.0, 0.0], atol=1e-9)
            frame = env.render()
            x, y = env.robot_state.position[0]
            assert at(frame, x + RADIUS, y) == CONTACT
            assert at(frame, x, y, (0.0, -0.2 * R_PX)) == PHASE_COLOURS["brake"]
    assert "brake" in seen and seen[0] == "drive"
    env.close()


@pytest.mark.parametrize("backend", ["ideal", "kinematic"])
def test_ideal_robots_have_no_phase_dot(backend):
    env = single(backend, step_mode="tick")
    assert at(env.render(), 5.0, 2.5, (0.0, -0.2 * R_PX)) == robot_colour(0)
    env.close()


def test_a_narrow_bumper_is_drawn_narrow():
    """physics_params bumper_arc = 60°: the band covers ± 30° of the heading only."""
    env = single("dynamic", step_mode="tick", physics_params={"bumper_arc": 60.0})
    frame = env.render()
    assert polar(frame, (5.0, 2.5), R_PX - 3, math.radians(20)) == BUMPER
    assert polar(frame, (5.0, 2.5), R_PX - 3, math.radians(45)) == robot_colour(0)
    env.close()


def test_cell_robot_marks_its_contact_at_its_cell():
    """The cell model's robots are points at cell centres: the contact is marked there."""
    env = BounceEnv(world=ROOM, backend="cell", render_mode="rgb_array")
    env.reset(seed=0, options={"start": {"position": [5.5, 2.5], "heading": 0.0}})
    state = env.robot_state
    assert state.blocked[0]
    assert at(env.render(), *state.position[0]) == CONTACT
    env.close()


def test_robots_blocked_by_each_other_mark_the_touching_point():
    """Two robots driving head-on meet at x = 5: both bumpers are pressed and the contact
    (5, 2.5) is marked; on every continuous backend."""
    for backend in sorted(BACKENDS):
        env = MultiBounceEnv(world=ROOM, n_robots=2, robot_radius=RADIUS,
                             render_mode="rgb_array", **BACKENDS[backend])
        env.reset(seed=0, options={"start": {"position": [[3.0, 2.5], [7.0, 2.5]],
                                             "heading": [0.0, math.pi]}})
        frame = env.render()
        assert env.robot_state.blocked.all(), backend
        assert at(frame, 5.0, 2.5) == CONTACT, backend
        assert polar(frame, (4.5, 2.5), R_PX - 3, math.radians(60)) == BUMPER_PRESSED
        assert polar(frame, (5.5, 2.5), R_PX - 3, math.pi - math.radians(60)) == BUMPER_PRESSED
        assert polar(frame, (4.5, 2.5), 0.6 * R_PX, 0.0) == INK
        assert polar(frame, (5.5, 2.5), 0.6 * R_PX, math.pi) == INK
        env.close()


@pytest.mark.parametrize("kind", ["single", "multi"])
def test_rendering_after_pickling_gives_identical_frames(kind):
    if kind == "single":
        env = single("dynamic")
        env.step(2)
    else:
        env = MultiBounceEnv(world=ROOM, n_robots=3, robot_radius=RADIUS, backend="pymunk",
                             render_mode="rgb_array", step_mode="tick")
        env.reset(seed=3)
        for _ in range(5):
            env.step(dict.fromkeys(env.agents, 1))
    frame = env.render()
    clone = pickle.loads(pickle.dumps(env))
    np.testing.assert_array_equal(clone.render(), frame)
    env.close()
    clone.close()


# -- the renderer's bumpers ------------------------------------------------------------------
def test_pressed_and_unpressed_bumpers_differ_only_on_the_band():
    pos, head = np.array([[5.0, 2.5]]), np.array([math.radians(30)])
    kw = {"arc": 180.0, "contacts": np.full((1, 2), np.nan)}
    up = GRID.draw(pos, head, RADIUS, bumpers=Bumpers(pressed=np.array([False]), **kw))
    down = GRID.draw(pos, head, RADIUS, bumpers=Bumpers(pressed=np.array([True]), **kw))
    changed = np.any(up != down, axis=2)
    rows, cols = np.nonzero(changed)
    (cx, cy), = GRID.to_pixels(pos)
    distance = np.hypot(cols - cx, rows - cy)
    assert changed.sum() > 50
    assert distance.max() <= R_PX + 1 and distance.min() >= R_PX - max(2, R_PX // 4) - 1
    # every changed pixel lies in the front half
    assert np.all((cols - cx) * math.cos(head[0]) - (rows - cy) * math.sin(head[0]) >= -1)
    assert np.all(down[changed] == BUMPER_PRESSED) and np.all(up[changed] == BUMPER)


def test_full_circle_bumper_and_tiny_robots():
    contacts = np.array([[1.0, 1.0]])
    full = GRID.draw(np.array([[5.0, 2.5]]), np.zeros(1), RADIUS,
                     bumpers=Bumpers(360.0, np.array([True]), np.full((1, 2), np.nan)))
    assert polar(full, (5.0, 2.5), R_PX - 2, math.pi) == BUMPER_PRESSED
    # a robot drawn below MIN_DETAIL_PX pixels gets no band nor dot, still its contact marker
    tiny = GRID.draw(np.array([[1.0, 1.0]]), np.zeros(1), 0.0,
                     bumpers=Bumpers(180.0, np.array([True]), contacts, ["brake"]))
    assert at(tiny, 1.0, 1.0) == CONTACT
    assert not np.any(np.all(tiny == BUMPER_PRESSED, axis=2))
    assert not np.any(np.all(tiny == PHASE_COLOURS["brake"], axis=2))
    # no headings: no band
    blind = GRID.draw(np.array([[5.0, 2.5]]), None, RADIUS,
                      bumpers=Bumpers(180.0, np.array([True]), np.full((1, 2), np.nan)))
    assert not np.any(np.all(blind == BUMPER_PRESSED, axis=2))


@pytest.mark.parametrize(("bumpers", "match"), [
    (Bumpers(0.0, np.zeros(1, bool), np.zeros((1, 2))), "arc"),
    (Bumpers(400.0, np.zeros(1, bool), np.zeros((1, 2))), "arc"),
    (Bumpers(180.0, np.zeros(2, bool), np.zeros((1, 2))), "pressed"),
    (Bumpers(180.0, np.zeros(1, bool), np.zeros(2)), "contacts"),
    (Bumpers(180.0, np.zeros(1, bool), np.zeros((1, 2)), ["flying"]), "phases"),
    (Bumpers(180.0, np.zeros(1, bool), np.zeros((1, 2)), []), "phases"),
    ("pressed", "Bumpers"),
])
def test_bad_bumpers_raise_config_error(bumpers, match):
    with pytest.raises(ConfigError, match=match):
        GRID.draw(np.array([[5.0, 2.5]]), np.zeros(1), RADIUS, bumpers=bumpers)
