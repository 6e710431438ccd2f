"""Robot–robot conflicts on the grid (docs/choices/multirobot.md, "Robot–robot conflicts on the grid"):
crossing diagonal moves, shared by the env's cell backend and the joint cell model."""

import numpy as np

from bounce_gym.cells import CellModel, JointCellModel, crossing, resolve_moves
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.worlds import World

SQUARE = World([(0, 0), (4, 0), (4, 4), (0, 4)], name="square_4x4")


def test_crossing_is_the_pair_of_diagonals_of_one_block():
    a0, a1 = np.array([0, 0]), np.array([1, 1])
    b0, b1 = np.array([0, 1]), np.array([1, 0])
    assert crossing(a0, a1, b0, b1) and crossing(b0, b1, a0, a1)
    assert not crossing(a0, a1, a1, a0)  # a swap: its own rule
    assert not crossing(a0, a1, b0, b0)  # b stays
    assert not crossing(a0, a1, b0, np.array([1, 2]))  # parallel diagonals
    assert not crossing(a0, np.array([1, 0]), b0, np.array([1, 1]))  # parallel verticals


def _crossing_start(model):
    """Robots at (row 1, col 1) heading NE and (row 1, col 2) heading NW: their diagonal moves
    cross at the corner shared by the four cells of rows 1-2, cols 1-2."""
    p = model.position_index[[1, 1], [1, 2]]
    return p, np.array([1, 3])  # bins of 45° and 135° (8 bins)


def test_crossing_diagonals_block_both_robots_in_the_joint_map():
    model = CellModel(SQUARE)
    p, k = _crossing_start(model)
    target = model.targets[k, p]
    assert crossing(model.position_rc[p[0]], model.position_rc[target[0]],
                    model.position_rc[p[1]], model.position_rc[target[1]])
    stays, blocker, pairs = resolve_moves(p[None], target[None], model.position_rc)
    assert stays.tolist() == [[True, True]]
    assert blocker.tolist() == [[1, 0]] and pairs.tolist() == [1]
    jm = JointCellModel(model, [90, 90])
    nxt, n_pairs = jm.step(model.cell_id(p, k), return_collisions=True)
    new_p, new_k = model.decode(nxt)
    assert np.array_equal(new_p, p) and np.array_equal(new_k, (k + 2) % 8) and n_pairs == 1


def test_env_cell_backend_blocks_crossing_diagonals_like_the_joint_map():
    model = CellModel(SQUARE)
    p, k = _crossing_start(model)
    env = MultiBounceEnv(world=SQUARE, n_robots=2, backend="cell", robot_radius=0.0,
                         angles=[90], step_mode="tick", robot_collisions="bounce")
    start = {"position": model.centres[p].tolist(), "heading": np.radians([45, 135]).tolist()}
    _, infos = env.reset(seed=0, options={"start": start})
    backend, state = env.core.dynamics.backend, env.core.state
    jm = JointCellModel(backend.model, [90, 90])
    x = backend.cells(state)
    assert np.array_equal(x, model.cell_id(p, k))
    for t in range(50):
        x = jm.step(x)
        _, _, _, _, infos = env.step(dict.fromkeys(env.agents, 0))
        assert np.array_equal(x, backend.cells(state))
        if t == 0:  # neither robot moved: both were blocked by the other and bumped
            assert np.allclose(state.position, model.centres[p])
            assert infos["robot_0"]["bumps"] == infos["robot_1"]["bumps"] == 1
    env.close()
