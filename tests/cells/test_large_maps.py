"""The cell backend builds on every map of the zoo and on a 10⁶-cell grid in bounded memory.

Nothing on its build path may hold all pairs of position cells: `too_close` once built the
(n, n) Chebyshev matrix of the minimum separation, which asked for 423 GiB on heptagon and
14.6 TiB on a 1,000 × 1,000 grid. It is now a `CloseCells` that looks the pairs up from the
cells' coordinates (O(n) memory). Memory is the traced peak (`tracemalloc`, which numpy's
arrays report to); no test here measures time.
"""

import tracemalloc

import numpy as np
import pytest

from bounce_gym.cells import CellModel, too_close
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import world_from_grid, zoo

MiB = 1 << 20


def _peak_bytes(build) -> int:
    """The traced peak of ``build()``, in bytes."""
    tracemalloc.start()
    try:
        build()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _build(world) -> None:
    """A lone robot and three colliding robots 1 cell apart on the cell backend: built, reset
    and stepped."""
    env = BounceEnv(world=world, backend="cell")
    env.reset(seed=0)
    env.step(0)
    env.close()
    multi = MultiBounceEnv(world=world, backend="cell", n_robots=3, robot_collisions="bounce",
                           min_sep_cells=1)
    multi.reset(seed=0)
    multi.step(dict.fromkeys(multi.agents, 0))
    multi.close()


@pytest.mark.parametrize("name", zoo.names())
def test_the_cell_backend_builds_on_every_zoo_world_at_its_default_step_length(name):
    """The largest maps (heptagon, simple_nonconv, l_shape, pinched_square, simple_bit) have
    150,000-210,000 free cells of the default step length; ~70 MiB at most is measured."""
    assert _peak_bytes(lambda: _build(zoo.get(name))) < 256 * MiB


def test_the_cell_backend_builds_on_a_million_cell_grid():
    """A 1,000 × 1,000 free grid: ~135 MiB is measured (the all-pairs matrix: 14.6 TiB)."""
    world = world_from_grid(np.ones((1000, 1000), dtype=bool), name="grid_1000x1000")
    assert CellModel(world).n_positions == 10**6
    assert _peak_bytes(lambda: _build(world)) < 1024 * MiB


def test_too_close_of_a_million_cells_stores_only_their_coordinates():
    rc = np.argwhere(np.ones((1000, 1000), dtype=bool))
    peak = _peak_bytes(lambda: too_close(rc, 2)[np.arange(10**6), np.arange(10**6)[::-1]])
    assert peak < 64 * MiB
    close = too_close(rc, 2)
    assert close.shape == (10**6, 10**6)
    assert close[0, 2002] and not close[0, 3003]  # (0, 0)-(2, 2) close, (0, 0)-(3, 3) not
    with pytest.raises(ConfigError, match="too large"):
        np.asarray(close)


def _brute_force(rc: np.ndarray, s: int) -> np.ndarray:
    return np.abs(rc[:, None, :] - rc[None, :, :]).max(axis=2) <= s


@pytest.mark.parametrize("seed", range(20))
def test_too_close_equals_the_all_pairs_matrix(seed):
    """Dense form, lookups (index arrays that broadcast, negative indices, scalars) and the
    KD-tree's pair list against the all-pairs Chebyshev matrix; repeated cells included."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 80))
    rc = rng.integers(0, int(rng.integers(1, 25)), size=(n, 2))
    for s in range(4):
        expected = _brute_force(rc, s)
        close = too_close(rc, s)
        assert close.shape == (n, n)
        assert np.array_equal(np.asarray(close), expected)
        i, j = rng.integers(-n, n, size=(3, 5, 1)), rng.integers(-n, n, size=(1, 5, 4))
        assert np.array_equal(close[i, j], expected[i, j])
        assert close[int(i.flat[0]), int(j.flat[-1])] == expected[i.flat[0], j.flat[-1]]
        assert np.array_equal(close.pairs(), np.argwhere(np.triu(expected, 1)))
