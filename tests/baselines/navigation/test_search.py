"""The breadth-first search over the simulator: shortest plans, proofs of unreachability, and
exact predictions of the sampled navigation planner in a deterministic world."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.navigation.sampled import SampledNavigationPlanner
from baselines.navigation.search import shortest_plan
from bounce_gym.cells.outcomes import BumpOutcomes

ENV_ID = "bounce_gym/BounceNavigation-v0"
KWARGS = {"angles": [45, 90, 135], "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}}


def _line(goal: int, size: int = 6):
    """A toy world: poses at x = 0 … size − 1 on a line; angle 0 steps right, angle 1 steps
    left (walls at both ends), angle 2 stays; the goal is met on the step into x = goal."""

    def simulate(action, point, heading):
        x = point[:, 0]
        nxt = np.clip(x + np.select([action == 0, action == 1], [1.0, -1.0], 0.0), 0, size - 1)
        end = np.column_stack((nxt, np.zeros(len(nxt))))
        out = BumpOutcomes(size, np.zeros(3), x.astype(np.int64), action, nxt.astype(np.int64),
                           np.ones(len(x), dtype=np.int64), point, end, heading)
        return out, (nxt == goal) & (x != goal)

    return simulate


def test_the_shortest_plan_and_the_poses_on_the_way():
    found = shortest_plan(_line(goal=5), np.array([1.0, 0.0]), 0.0, 3, None, 50, 1_000, 1.0, 1.0)
    assert found.found and found.actions == (0, 0, 0, 0)
    np.testing.assert_array_equal(found.points[:, 0], [1, 2, 3, 4])
    back = shortest_plan(_line(goal=0), np.array([3.0, 0.0]), 0.0, 3, None, 50, 1_000, 1.0, 1.0)
    assert back.actions == (1, 1, 1)


def test_limits_and_exhaustion_are_told_apart():
    unreachable = shortest_plan(_line(goal=9), np.array([1.0, 0.0]), 0.0, 3, None, 50, 1_000,
                                1.0, 1.0)
    assert not unreachable.found and unreachable.exhausted
    too_short = shortest_plan(_line(goal=5), np.array([1.0, 0.0]), 0.0, 3, None, 2, 1_000,
                              1.0, 1.0)
    assert not too_short.found and not too_short.exhausted
    too_small = shortest_plan(_line(goal=5), np.array([1.0, 0.0]), 0.0, 3, None, 50, 2, 1.0, 1.0)
    assert not too_small.found and not too_small.exhausted


def _episode(cell, env, planner, seed: int) -> bool:
    """One episode of ``env`` with start and goal drawn as on the ``cell`` env (cell centres,
    bin headings), the planner handed no ``info``: whether it reached the goal."""
    cell.reset(seed=seed)
    task = cell.unwrapped.task
    options = {k: {"position": pose[0][0].tolist(), "heading": float(pose[1][0])}
               for k, pose in (("start", task.start), ("goal", task.goal))}
    obs, info = env.reset(seed=seed, options=options)
    planner.reset(env)
    while True:
        obs, _, terminated, truncated, info = env.step(planner.act(obs, {}))
        if terminated or truncated:
            return bool(info["is_success"])


@pytest.mark.parametrize("seed", range(10_000, 10_006))
def test_predictions_are_exact_in_a_deterministic_world(seed):
    """Without noise the belief is one exact pose and the search decides: the planner predicts
    1 exactly where it then reaches the goal, 0 where no sequence of angles can. Start and goal
    are drawn as on the cell backend (cell centres, bin headings), where the poses reachable
    at bumps are few enough for the search to expand all of them."""
    cell = gym.make(ENV_ID, backend="cell", **KWARGS)
    env = gym.make(ENV_ID, backend="kinematic", **KWARGS)
    planner = SampledNavigationPlanner(samples=4, cell_size=0.5, depth=1, reach=3, cache=False)
    success = _episode(cell, env, planner, seed)
    assert planner.predicted_success in (0.0, 1.0)
    assert success == (planner.predicted_success == 1.0)


@pytest.mark.parametrize("map_seed", [1, 2])
def test_predicted_equals_measured_on_generated_maps(map_seed):
    """On two generated grid maps (random rectangular obstacles), ten episodes each: the mean
    predicted success lies inside the 95 % Wilson interval of the measured success — here,
    without noise, every episode's prediction is its outcome."""
    from bounce_gym.worlds.generators import random_grid
    from bounce_gym_experiments.stats import wilson_interval

    world = random_grid(np.random.default_rng(map_seed), 7, 7, 3, 2, name=f"grid{map_seed}")
    kwargs = dict(KWARGS, world=world)
    cell = gym.make(ENV_ID, backend="cell", **kwargs)
    env = gym.make(ENV_ID, backend="kinematic", **kwargs)
    planner = SampledNavigationPlanner(samples=4, cell_size=0.5, depth=1, reach=3, cache=False)
    predicted, measured = [], []
    for seed in range(10_000, 10_010):
        measured.append(_episode(cell, env, planner, seed))
        predicted.append(planner.predicted_success)
    assert predicted == [float(m) for m in measured]
    low, high = wilson_interval(sum(measured), len(measured))
    assert low <= np.mean(predicted) <= high
    assert sum(measured) > 0
