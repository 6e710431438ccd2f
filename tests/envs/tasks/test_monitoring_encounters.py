"""Monitoring's encounter count equals the count over all robot pairs, on crowded random ends."""

import numpy as np
import pytest

from bounce_gym.envs.multi_bounce_env import MultiBounceEnv


def all_pairs_encounters(points, radius, cell):
    i, j = np.triu_indices(len(points), k=1)
    if cell:
        cells = np.floor(points)  # grid_10x10: bounds start at 0, step_length 1
        return int(np.all(cells[i] == cells[j], axis=1).sum())
    return int((np.hypot(*(points[i] - points[j]).T) < 2 * radius).sum())


@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_encounters_equal_the_all_pairs_count(radius):
    env = MultiBounceEnv(world="grid_10x10", n_robots=40, task="monitoring", robot_radius=radius,
                         robot_collisions="ignore")
    task = env.core.task
    rng = np.random.default_rng(0)
    found = 0
    for _ in range(200):
        points = rng.uniform(0, 10, (40, 2))
        points[:5] = points[5:10] + rng.normal(0, 0.2, (5, 2))  # some close pairs for sure
        points[10] = points[11]  # and one on top of another
        count = task._encounters(points)
        assert count == all_pairs_encounters(points, radius, cell=radius == 0)
        found += count
    assert found > 200
