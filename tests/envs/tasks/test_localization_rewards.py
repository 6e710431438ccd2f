"""The localization task ranks policies by time to localize: bits of uncertainty removed minus
a cost per tick until the filter first reports ``localized``."""

import itertools
import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import bounce_gym  # noqa: F401  (registers the ids)
from bounce_gym.errors import ConfigError

LOC = "bounce_gym/BounceLocalization-v0"


def episode(env, seed: int, choose) -> dict:
    _, info = env.reset(seed=seed)
    start = {"candidates": info["candidates"], "ticks": info["ticks"]}
    total, done, t = 0.0, False, 0
    while not done:
        _, reward, terminated, truncated, info = env.step(choose(t))
        total += reward
        done, t = terminated or truncated, t + 1
    return {"return": total, "localized": info["localized"], "start": start,
            "candidates": info["candidates"], "ticks_to_localize": info.get("ticks_to_localize")}


def test_the_registered_id_chooses_between_two_angles():
    env = gym.make(LOC)
    assert env.action_space == gym.spaces.Discrete(2)
    assert np.degrees(env.unwrapped.options.angles[0]).tolist() == pytest.approx([45.0, 135.0])
    assert env.unwrapped.task.tick_cost == 0.1
    assert env.spec.max_episode_steps == 200


def test_returns_rank_localizers_by_ticks_and_above_every_failure():
    env = gym.make(LOC)
    rng = np.random.default_rng(0)
    random_angles = rng.integers(2, size=1000)
    policies = {"45°": lambda t: 0, "135°": lambda t: 1, "alternate": lambda t: t % 2,
                "random": lambda t: int(random_angles[t])}
    compared = failures = 0
    for seed in range(6):
        runs = [episode(env, seed, choose) for choose in policies.values()]
        for run in runs:
            if run["localized"]:  # the return is exactly the bits gained minus the ticks
                spent = run["ticks_to_localize"] - run["start"]["ticks"]
                bits = math.log2(run["start"]["candidates"]) - math.log2(run["candidates"])
                assert run["return"] == pytest.approx(bits - 0.1 * spent)
        for a, b in itertools.permutations(runs, 2):
            if a["localized"] and not b["localized"]:
                assert a["return"] > b["return"]
                failures += 1
            elif a["localized"] and b["localized"] and a["candidates"] == b["candidates"] \
                    and a["ticks_to_localize"] < b["ticks_to_localize"]:
                assert a["return"] > b["return"]
                compared += 1
    assert compared >= 5 and failures >= 1


@pytest.mark.parametrize("tick_cost", [0.0, -1.0, "0.1", True])
def test_tick_cost_must_be_a_positive_number(tick_cost):
    with pytest.raises(ConfigError, match=r"^tick_cost: "):
        gym.make(LOC, task_kwargs={"filter_factory": "combinatorial", "tick_cost": tick_cost})


@pytest.mark.parametrize("step_mode", ["bounce", "tick"])
def test_gymnasium_check_env_with_a_tick_cost(step_mode):
    env = gym.make(LOC, step_mode=step_mode,
                   task_kwargs={"filter_factory": "combinatorial", "tick_cost": 0.5})
    check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.slow  # ~10 s each
@pytest.mark.parametrize("step_mode", ["bounce", "tick"])
def test_a_long_episode_keeps_no_per_step_state(step_mode):
    """Step time stays flat over a long episode because nothing grows with the steps taken:
    after a warm-up, three windows of 5,000 steps each are traced, and from the end of one
    window to the end of the next the memory that the package's own code holds grows by less
    than 16 KiB at least once. A history kept per step (a list in the task, the filter or the
    info) grows by at least 8 bytes a step in every window, far past the bound; a cache that
    fills once, or an array whose size varies with the candidates, changes one window only."""
    import gc
    import tracemalloc

    env = gym.make(LOC, step_mode=step_mode, max_episode_steps=None, task_kwargs={
        "filter_factory": "combinatorial", "terminate_when_localized": False}).unwrapped
    env.reset(seed=0)
    actions = np.random.default_rng(0).integers(0, env.action_space.n, size=16_000).tolist()
    ours = [tracemalloc.Filter(True, "*bounce_gym*")]

    def run(part):
        for action in part:
            env.step(action)
        gc.collect()
        return tracemalloc.take_snapshot().filter_traces(ours)

    for action in actions[:1_000]:
        env.step(action)
    tracemalloc.start()
    try:
        ends = [run(actions[start:start + 5_000]) for start in (1_000, 6_000, 11_000)]
    finally:
        tracemalloc.stop()
    growth = [later.compare_to(earlier, "lineno") for earlier, later in itertools.pairwise(ends)]
    grown = [sum(stat.size_diff for stat in g) for g in growth]
    assert min(grown) < 16_384, [str(stat) for g in growth for stat in g[:2]]  # bytes
    assert env.unwrapped.core.task.filter.size <= env.unwrapped.cell_model().n_cells
