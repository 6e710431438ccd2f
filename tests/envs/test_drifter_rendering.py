"""Drawing drifters: frames of both envs in both current styles, what the pixels show, the human
window, and rendering that changes nothing."""

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.cells import DOWN, DRIFT
from bounce_gym.envs.drifters.env import DrifterEnv
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv
from bounce_gym.envs.render.flow_view import LAND, WATER, FlowRenderer
from bounce_gym.envs.render.renderer import robot_colour
from bounce_gym.flows import get_flow

THREE = dict(flow="two_sink", flow_kwargs={"n_layers": 3})


def _pixel(renderer, frame, x, y):
    (col, row), = np.rint(renderer.to_pixels(renderer.display(np.array([[x, y]])))).astype(int)
    return tuple(int(v) for v in frame[row, col])


@pytest.mark.parametrize("style", ["arrows", "streamlines"])
@pytest.mark.parametrize("backend", ["cell", "continuous"])
def test_check_env_renders_every_mode(style, backend):
    env = gym.make("bounce_gym/Drifter-v0", render_mode="rgb_array", field_style=style,
                   backend=backend)
    check_env(env.unwrapped)
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3


def test_pixels_show_land_water_goal_and_the_drifter():
    env = DrifterEnv(**THREE, render_mode="rgb_array", goal={"cell": (0, 3, 3), "halo": 1})
    _, info = env.reset(seed=0, options={"start": (0, 12, 12)})
    frame = env.render()
    r = env._renderer
    field = env.flow
    assert _pixel(r, frame, field.x[27], field.y[3]) == LAND  # the eastern strip
    # a water cell away from arrows and drifter: the cell's corner region
    corner = _pixel(r, frame, field.x[14] + 420.0, field.y[18] + 420.0)
    assert corner == WATER
    goal = _pixel(r, frame, field.x[3] + 300.0, field.y[3] + 300.0)
    assert goal[1] > goal[0] and goal[1] > goal[2]  # green
    x, y = info["position"]
    assert _pixel(r, frame, x, y) == robot_colour(0)


def test_a_drifter_in_a_deeper_layer_shows_that_layer_and_a_ring_elsewhere():
    env = MultiDrifterEnv(**THREE, n_drifters=2, deploy=[(0, 12, 12), (0, 4, 16)],
                          render_mode="rgb_array")
    env.reset(seed=0)
    env.step({"drifter_0": DRIFT, "drifter_1": DOWN})
    frame = env.render()  # the fleet draws the surface
    centre = env.core.fleet.positions()[1]
    assert _pixel(env._renderer, frame, *centre) != robot_colour(1)  # a ring, hollow inside
    single = DrifterEnv(**THREE, render_mode="rgb_array", task="cover")
    single.reset(seed=0, options={"start": (0, 12, 12)})
    single.step(DOWN)
    single.render()
    assert single._render_layer() == 1


def test_visited_cells_are_shaded():
    env = DrifterEnv(**THREE, render_mode="rgb_array", task="cover")
    _, info = env.reset(seed=0, options={"start": (0, 16, 19)})
    start = info["position"]
    for _ in range(6):
        _, _, _, _, info = env.step(DRIFT)
    assert not np.array_equal(info["position"], start)
    frame = env.render()
    corner = _pixel(env._renderer, frame, start[0] + 420.0, start[1] + 420.0)
    assert corner != WATER and corner[2] > corner[0]  # bluish shade over the water


def test_lonlat_map_keeps_its_shape():
    field = get_flow("scb_like")
    r = FlowRenderer(field, width=640, margin=0)
    # 0.56 degrees of longitude at 33.5 N against 0.40 degrees of latitude (+ half cells)
    width_m = (0.56 + 0.02) * np.cos(np.radians(33.5))
    height_m = 0.40 + 0.02
    assert r.height / r.width == pytest.approx(height_m / width_m, rel=0.01)


def test_rendering_changes_nothing_and_pickles():
    plain = DrifterEnv(**THREE, backend="continuous", diffusivity=10.0)
    drawn = DrifterEnv(**THREE, backend="continuous", diffusivity=10.0, render_mode="rgb_array",
                       field_style="streamlines")
    a, b = [plain.reset(seed=2)], [drawn.reset(seed=2)]
    for k in range(8):
        a.append(plain.step(k % 3))
        b.append(drawn.step(k % 3))
        drawn.render()
    assert data_equivalence(a, b, exact=True)
    clone = pickle.loads(pickle.dumps(drawn))
    assert np.array_equal(clone.render(), drawn.render())


def test_human_mode_opens_a_window_headless():
    env = DrifterEnv(**THREE, render_mode="human")
    env.reset(seed=0)
    assert env.render() is None
    env.step(DRIFT)
    env.close()
    env.close()


def test_render_without_mode_warns():
    env = DrifterEnv(**THREE)
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None
