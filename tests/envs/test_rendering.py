"""Rendering: headless frames, layers, the human window, pickling and GIF export."""

import os
import pickle
import subprocess
import sys
import textwrap

import gymnasium
import numpy as np
import pytest
from PIL import Image

from bounce_gym import worlds
from bounce_gym.envs.render import gif
from bounce_gym.envs.render.gif import record_episode, save_gif
from bounce_gym.envs.render.renderer import (
    BLOCKED_RING,
    EXTERIOR,
    FREE,
    HOLE,
    WALL,
    Renderer,
    RenderLayers,
    robot_colour,
)
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

# A 10 x 5 room with a 2 x 1 obstacle in the middle.
ROOM = World(
    [(0, 0), (10, 0), (10, 5), (0, 5)],
    holes=[[(4, 2), (6, 2), (6, 3), (4, 3)]],
    name="room_with_pillar",
)


@pytest.fixture
def renderer():
    r = Renderer(ROOM, width=400, margin=10, grid=False)
    yield r
    r.close()


def pixel(renderer, frame, x, y):
    (col, row), = np.rint(renderer.to_pixels(np.array([[x, y]]))).astype(int)
    return tuple(int(v) for v in frame[row, col])


def empty(renderer, **kw):
    return renderer.draw(np.zeros((0, 2)), np.zeros(0), 0.0, **kw)


# -- frames ---------------------------------------------------------------------------------
def test_frame_shape_dtype_and_range(renderer):
    frame = renderer.draw(np.array([[2.5, 1.5]]), np.array([0.3]), 0.4)
    assert isinstance(frame, np.ndarray)
    assert frame.dtype == np.uint8
    assert frame.shape == renderer.shape == (renderer.height, 400, 3)
    # 10 x 5 world in 380 pixels: 38 px per unit, height 5 * 38 + 2 * 10
    assert renderer.scale == pytest.approx(38.0)
    assert renderer.height == 210
    assert frame.min() >= 0 and frame.max() <= 255
    assert frame.flags.c_contiguous


def test_default_renderer_on_zoo_world():
    world = worlds.get("two_rooms")
    r = Renderer(world)
    frame = r.draw(world.sample_free(np.random.default_rng(0), 3, 0.3), np.zeros(3), 0.3)
    assert frame.shape == (r.height, 640, 3)
    xmin, ymin, xmax, ymax = world.bounds
    assert r.height == pytest.approx((ymax - ymin) / (xmax - xmin) * (640 - 32) + 32, abs=1)


def test_wall_free_hole_and_exterior_pixels_differ(renderer):
    frame = empty(renderer)
    free = pixel(renderer, frame, 2.5, 1.5)
    wall = pixel(renderer, frame, 0.0, 2.5)
    hole_wall = pixel(renderer, frame, 4.0, 2.5)
    hole = pixel(renderer, frame, 5.0, 2.5)
    outside = tuple(int(v) for v in frame[2, 2])  # in the margin
    assert free == FREE
    assert wall == WALL and hole_wall == WALL
    assert hole == HOLE
    assert outside == EXTERIOR
    assert len({free, wall, hole, outside}) == 4


def test_grid_only_in_free_space():
    r = Renderer(ROOM, width=400, margin=10, grid=True)
    plain = empty(Renderer(ROOM, width=400, margin=10, grid=False))
    frame = empty(r)
    assert not np.array_equal(frame, plain)
    assert pixel(r, frame, 5.0, 2.5) == HOLE  # the hole hides the grid
    assert tuple(int(v) for v in frame[2, 2]) == EXTERIOR


def test_robot_colours_its_pixels(renderer):
    frame = renderer.draw(np.array([[2.5, 1.5]]), np.array([0.0]), 0.5)
    (col, row), = np.rint(renderer.to_pixels(np.array([[2.5, 1.5]]))).astype(int)
    # heading 0 points right (+x): the heading line covers the right half, so look left
    assert tuple(frame[row, col - 5]) == robot_colour(0)
    assert tuple(frame[row - 5, col]) == robot_colour(0)
    # a second robot has a different colour
    frame2 = renderer.draw(np.array([[2.5, 1.5], [8.0, 1.0]]), np.array([0.0, 0.0]), 0.5)
    (col2, row2), = np.rint(renderer.to_pixels(np.array([[8.0, 1.0]]))).astype(int)
    assert tuple(frame2[row2, col2 - 5]) == robot_colour(1) != robot_colour(0)


def test_point_robot_is_visible(renderer):
    frame = renderer.draw(np.array([[2.5, 1.5]]), np.array([0.0]), 0.0)
    (col, row), = np.rint(renderer.to_pixels(np.array([[2.5, 1.5]]))).astype(int)
    assert tuple(frame[row, col - 2]) == robot_colour(0)
    assert tuple(frame[row + 2, col]) == robot_colour(0)


def test_blocked_robot_is_outlined(renderer):
    pos = np.array([[2.5, 1.5]])
    free = renderer.draw(pos, np.array([0.0]), 0.5, blocked=np.array([False]))
    hit = renderer.draw(pos, np.array([0.0]), 0.5, blocked=np.array([True]))
    (col, row), = np.rint(renderer.to_pixels(pos)).astype(int)
    r_px = round(0.5 * renderer.scale)
    assert tuple(free[row, col - r_px - 2]) == FREE
    assert tuple(hit[row, col - r_px - 2]) == BLOCKED_RING


def test_frames_are_fresh_arrays(renderer):
    args = (np.array([[2.5, 1.5]]), np.array([1.0]), 0.4)
    first = renderer.draw(*args)
    second = renderer.draw(*args)
    assert first is not second
    assert not np.shares_memory(first, second)
    assert np.array_equal(first, second)
    first[:] = 0
    assert np.array_equal(renderer.draw(*args), second)


def test_y_axis_points_up(renderer):
    base = empty(renderer)
    top = renderer.draw(np.array([[8.0, 4.6]]), np.array([np.pi / 2]), 0.3)
    bottom = renderer.draw(np.array([[8.0, 0.4]]), np.array([np.pi / 2]), 0.3)
    top_rows = np.flatnonzero(np.any(top != base, axis=(1, 2)))
    bottom_rows = np.flatnonzero(np.any(bottom != base, axis=(1, 2)))
    half = renderer.height // 2
    assert top_rows.size and top_rows.max() < half
    assert bottom_rows.size and bottom_rows.min() > half
    # heading pi/2 (+y) draws the heading line upwards from the centre
    (col, row), = np.rint(renderer.to_pixels(np.array([[8.0, 0.4]]))).astype(int)
    r_px = round(0.3 * renderer.scale)
    assert np.any(bottom[row - r_px - 3, col - 1 : col + 2] != np.array(FREE))
    assert np.all(bottom[row + r_px + 3, col - 1 : col + 2] == np.array(FREE))


def test_heatmap_colours_its_cells_row_zero_at_bottom(renderer):
    values = np.zeros((5, 10))
    values[0, 0] = 3.0  # bottom-left cell
    values[0, 9] = 1.0  # bottom-right cell, a third as hot
    frame = empty(renderer, layers=RenderLayers(heatmap=(values, (0.0, 0.0), 1.0)))
    plain = empty(renderer)
    hot = pixel(renderer, frame, 0.5, 0.5)
    warm = pixel(renderer, frame, 9.5, 0.5)
    assert hot != pixel(renderer, plain, 0.5, 0.5)
    assert warm != pixel(renderer, plain, 9.5, 0.5)
    assert hot != warm
    # the top-left cell (row 4) has value 0: untouched
    assert pixel(renderer, frame, 0.5, 4.5) == FREE
    # the heatmap stays under the walls and the hole
    assert pixel(renderer, frame, 0.0, 0.5) == WALL


def test_heatmap_rejects_bad_values(renderer):
    with pytest.raises(ConfigError, match="heatmap"):
        empty(renderer, layers=RenderLayers(heatmap=(-np.ones((2, 2)), (0, 0), 1.0)))
    with pytest.raises(ConfigError, match="cell_size"):
        empty(renderer, layers=RenderLayers(heatmap=(np.ones((2, 2)), (0, 0), 0.0)))
    with pytest.raises(ConfigError, match="heatmap"):
        empty(renderer, layers=RenderLayers(heatmap=np.ones((2, 2))))


def test_all_layers_draw(renderer):
    t = np.linspace(0.0, 1.0, 20)
    layers = RenderLayers(
        trails=[np.column_stack((1 + 2 * t, 1 + 3 * t)), np.zeros((0, 2))],
        goal=(8.5, 3.5, 0.5, np.pi / 2, np.pi / 8),
        regions=[np.array([[7, 0.5], [9, 0.5], [9, 1.5], [7, 1.5]])],
        heatmap=(np.ones((5, 10)), (0.0, 0.0), 1.0),
        labels=["tick 120  bumps 14", "second line"],
    )
    pos = np.array([[3.0, 4.0], [1.0, 1.0]])
    frame = renderer.draw(pos, np.zeros(2), 0.3, layers=layers, blocked=np.array([True, False]))
    assert frame.shape == renderer.shape
    plain = renderer.draw(pos, np.zeros(2), 0.3)
    goal_px = pixel(renderer, frame, 8.5, 3.2)
    assert goal_px != pixel(renderer, plain, 8.5, 3.2)
    assert pixel(renderer, frame, 8.0, 1.0) != pixel(renderer, plain, 8.0, 1.0)  # region
    # goal as (x, y, r) and with a full-circle tolerance
    renderer.draw(pos, None, 0.3, layers=RenderLayers(goal=(8.5, 3.5, 0.5)))
    renderer.draw(pos, None, 0.3, layers=RenderLayers(goal=(8.5, 3.5, 0.5, 0.0, np.pi)))
    with pytest.raises(ConfigError, match="goal"):
        renderer.draw(pos, None, 0.3, layers=RenderLayers(goal=(1.0, 2.0)))


def test_bad_inputs_raise_config_error(renderer):
    with pytest.raises(ConfigError, match="positions"):
        renderer.draw(np.zeros(3), np.zeros(1), 0.1)
    with pytest.raises(ConfigError, match="headings"):
        renderer.draw(np.zeros((2, 2)), np.zeros(3), 0.1)
    with pytest.raises(ConfigError, match="radius"):
        renderer.draw(np.zeros((2, 2)), np.zeros(2), np.ones(3))
    with pytest.raises(ConfigError, match="radius"):
        renderer.draw(np.zeros((2, 2)), np.zeros(2), -1.0)
    with pytest.raises(ConfigError, match="blocked"):
        renderer.draw(np.zeros((2, 2)), np.zeros(2), 0.1, blocked=[True])
    with pytest.raises(ConfigError, match="width"):
        Renderer(ROOM, width=10)
    with pytest.raises(ConfigError, match="world"):
        Renderer("two_rooms")


def test_missing_pygame_raises_dependency_not_installed(renderer, monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)
    with pytest.raises(gymnasium.error.DependencyNotInstalled, match="pip install"):
        empty(renderer)


# -- pygame initialisation ---------------------------------------------------------------------
def test_pygame_selective_init():
    """Rendering (frames, labels, a window) never calls pygame.init() nor starts the mixer.

    In pygame 2.6 ``pygame.get_init()`` is True only after ``pygame.init()`` (initialising
    ``pygame.display`` or ``pygame.font`` alone leaves it False), so it detects exactly that
    call. The check runs in a fresh interpreter because other tests in this session (or other
    libraries) may have initialised pygame already.
    """
    script = textwrap.dedent(
        """
        import numpy as np
        import pygame
        from bounce_gym import worlds
        from bounce_gym.envs.render.renderer import Renderer, RenderLayers
        world = worlds.get("two_rooms")
        r = Renderer(world)
        frame = r.draw(np.array([[2.0, 2.0]]), np.zeros(1), 0.3,
                       layers=RenderLayers(labels=["tick 1"]))
        assert pygame.display.get_init() is False, "rgb_array must not touch the display"
        r.show(frame, fps=0)
        shown = pygame.display.get_init()
        r.close()
        print(pygame.get_init(), pygame.mixer.get_init(), shown, pygame.display.get_init())
        """
    )
    env = dict(os.environ, SDL_VIDEODRIVER="dummy", SDL_AUDIODRIVER="dummy")
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=60
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-4:] == ["False", "None", "True", "False"]


def test_human_mode_show_and_close_twice(renderer):
    import pygame

    frame = renderer.draw(np.array([[2.5, 1.5]]), np.array([0.0]), 0.4)
    renderer.show(frame, fps=1000)
    renderer.show(frame, fps=1000)
    assert pygame.display.get_init()
    assert pygame.display.get_surface().get_size() == (renderer.width, renderer.height)
    assert pygame.mixer.get_init() is None
    renderer.close()
    renderer.close()
    assert not pygame.display.get_init()
    with pytest.raises(ConfigError, match="frame"):
        renderer.show(frame[..., 0])


# -- pickling -----------------------------------------------------------------------------------
def test_pickle_after_drawing_draws_identical_frames(renderer):
    layers = RenderLayers(
        trails=[np.array([[1.0, 1.0], [2.0, 2.0], [3.0, 1.5]])],
        heatmap=(np.arange(50.0).reshape(5, 10), (0.0, 0.0), 1.0),
        labels=["tick 3"],
    )
    args = (np.array([[3.0, 1.5]]), np.array([0.5]), 0.4)
    frame = renderer.draw(*args, layers=layers)
    renderer.show(frame, fps=0)
    clone = pickle.loads(pickle.dumps(renderer))
    assert clone.world == renderer.world
    assert np.array_equal(clone.draw(*args, layers=layers), frame)
    clone.close()  # never opened a window: a no-op


# -- GIFs ---------------------------------------------------------------------------------------
def _frames(n=4, shape=(20, 30, 3)):
    return [np.full(shape, 40 * k, dtype=np.uint8) for k in range(n)]


def test_save_gif_round_trip(tmp_path):
    out = save_gif(_frames(), tmp_path / "anim.gif", fps=5)
    assert out == tmp_path / "anim.gif"
    with Image.open(out) as im:
        assert im.format == "GIF"
        assert im.n_frames == 4
        assert im.size == (30, 20)
        assert im.info.get("loop") == 0
        assert im.info.get("duration") == 200
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.gif"]


def test_save_gif_creates_parent_and_replaces(tmp_path):
    path = tmp_path / "sub" / "anim.gif"
    save_gif(_frames(2), path)
    save_gif(_frames(3), str(path))
    with Image.open(path) as im:
        assert im.n_frames == 3
    assert sorted(p.name for p in path.parent.iterdir()) == ["anim.gif"]


def test_save_gif_is_atomic_on_failure(tmp_path, monkeypatch):
    path = tmp_path / "anim.gif"
    save_gif(_frames(2), path)
    before = path.read_bytes()

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(Image.Image, "save", boom)
    with pytest.raises(OSError, match="disk full"):
        save_gif(_frames(3), path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.gif"]


@pytest.mark.parametrize(
    ("frames", "match"),
    [
        ([], "empty"),
        ([np.zeros((4, 4, 3), dtype=np.float32)], "uint8"),
        ([np.zeros((4, 4), dtype=np.uint8)], "shape"),
        ([np.zeros((4, 4, 4), dtype=np.uint8)], "shape"),
        ([np.zeros((4, 4, 3), dtype=np.uint8), np.zeros((4, 5, 3), dtype=np.uint8)], "same"),
        (["not an array"], "numpy"),
    ],
)
def test_save_gif_rejects_bad_frames(tmp_path, frames, match):
    with pytest.raises(ConfigError, match=match):
        save_gif(frames, tmp_path / "bad.gif")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fps", [0, -1, float("nan"), "fast"])
def test_save_gif_rejects_bad_fps(tmp_path, fps):
    with pytest.raises(ConfigError, match="fps"):
        save_gif(_frames(2), tmp_path / "bad.gif", fps=fps)


def test_save_gif_of_rendered_frames(tmp_path, renderer):
    frames = [
        renderer.draw(np.array([[1.0 + k, 1.0]]), np.array([0.0]), 0.3) for k in range(3)
    ]
    path = save_gif(frames, tmp_path / "robot.gif")
    with Image.open(path) as im:
        assert im.n_frames == 3
        assert im.size == (renderer.width, renderer.height)


def test_record_episode_cartpole(tmp_path):
    env = gymnasium.make("CartPole-v1", render_mode="rgb_array")
    try:
        a = record_episode(env, None, tmp_path / "a.gif", max_steps=5, seed=3)
        b = record_episode(env, None, tmp_path / "b.gif", max_steps=5, seed=3)
        c = record_episode(env, lambda obs, info: 1, tmp_path / "c.gif", max_steps=5, seed=0)
    finally:
        env.close()
    with Image.open(a) as im:
        assert 2 <= im.n_frames <= 6  # reset frame + 5 steps (identical frames may merge)
        assert im.size == (600, 400)
    assert a.read_bytes() == b.read_bytes()  # seeded env and action space: reproducible
    assert c.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "b.gif", "c.gif"]


def test_record_episode_counts_frames(tmp_path, monkeypatch):
    env = gymnasium.make("CartPole-v1", render_mode="rgb_array")
    seen = {}

    def fake_save(frames, path, fps=10, width=None):
        seen["n"], seen["fps"] = len(frames), fps
        return path

    monkeypatch.setattr(gif, "save_gif", fake_save)
    try:
        record_episode(env, lambda obs, info: 0, tmp_path / "x.gif", max_steps=5, seed=0)
        assert seen == {"n": 6, "fps": 10}
        record_episode(env, lambda obs, info: 0, tmp_path / "x.gif", max_steps=0, fps=None)
        assert seen == {"n": 1, "fps": env.metadata["render_fps"]}
        # always pushing left ends the episode (pole falls) well before 500 steps
        record_episode(env, lambda obs, info: 0, tmp_path / "x.gif", max_steps=500, seed=0)
        assert 2 < seen["n"] < 100
    finally:
        env.close()


def test_record_episode_needs_rgb_array(tmp_path):
    env = gymnasium.make("CartPole-v1")
    try:
        with pytest.raises(ConfigError, match="rgb_array"):
            record_episode(env, None, tmp_path / "x.gif", max_steps=5)
    finally:
        env.close()
    env = gymnasium.make("CartPole-v1", render_mode="rgb_array")
    try:
        with pytest.raises(ConfigError, match="max_steps"):
            record_episode(env, None, tmp_path / "x.gif", max_steps=-1)
    finally:
        env.close()


def test_save_gif_can_downscale(tmp_path):
    from PIL import Image

    from bounce_gym.envs.render.gif import save_gif
    from bounce_gym.errors import ConfigError

    frames = [np.full((40, 80, 3), v, dtype=np.uint8) for v in (0, 128, 255)]
    out = save_gif(frames, tmp_path / "small.gif", width=20)
    assert Image.open(out).size == (20, 10)
    with pytest.raises(ConfigError, match="width"):
        save_gif(frames, tmp_path / "bad.gif", width=0)
