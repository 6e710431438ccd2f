"""`BounceVectorEnv` against N ``gym.make`` envs in Gymnasium's SyncVectorEnv."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import bounce_gym  # noqa: F401
from bounce_gym.envs.vector_env import BounceVectorEnv
from bounce_gym.errors import ActionError, ConfigError

IDS = ["bounce_gym/Bounce-v0", "bounce_gym/BounceNavigation-v0", "bounce_gym/BounceCoverage-v0"]
CASES = [(env_id, kwargs) for env_id in IDS for kwargs in (
    {}, {"action_type": "continuous"}, {"backend": "cell"})]


def _pair(env_id, n, **kwargs):
    native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    sync = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **kwargs)
    return native, sync


def _same_step(a, b, where):
    for name, x, y in zip(("obs", "reward", "terminated", "truncated"), a[:4], b[:4],
                          strict=True):
        assert x.dtype == y.dtype and np.array_equal(x, y), (where, name, x, y)
    _same_infos(a[4], b[4], where)


def _same_infos(mine, theirs, where):
    # documented difference: ``cell`` is an (N, 2) int array, not an object array of tuples
    assert set(mine) == set(theirs), (where, set(mine) ^ set(theirs))
    for key, value in theirs.items():
        if key == "cell":
            expect = np.array([c if c is not None else (0, 0) for c in value])
            assert np.array_equal(mine[key][theirs["_cell"]], expect[theirs["_cell"]]), where
        else:
            assert np.array_equal(mine[key], value), (where, key, mine[key], value)
            assert mine[key].dtype == value.dtype, (where, key)


def _steps_alike(native, sync, steps: int, action_seed: int) -> int:
    """Step both envs with the same random actions, checking every step alike; returns how
    many episodes ended."""
    native.action_space.seed(action_seed)
    ended = 0
    for t in range(steps):
        actions = native.action_space.sample()
        out = native.step(actions)
        _same_step(out, sync.step(actions), t)
        ended += int((out[2] | out[3]).sum())
    return ended


@pytest.mark.parametrize(("env_id", "kwargs"), CASES)
def test_same_episodes_as_sync_vector_env(env_id, kwargs):
    """Same seeds and actions: identical observations, rewards, flags and infos, across
    truncations, terminations and next-step autoresets."""
    n = 5
    native, sync = _pair(env_id, n, max_episode_steps=40, **kwargs)
    a, b = native.reset(seed=11), sync.reset(seed=11)
    assert np.array_equal(a[0], b[0])
    _same_infos(a[1], b[1], "reset")
    assert _steps_alike(native, sync, 130, action_seed=2) >= n  # every env autoreset
    a, b = native.reset(seed=5), sync.reset(seed=5)  # a second reset with a new seed
    assert np.array_equal(a[0], b[0])


@pytest.mark.parametrize(("n", "kwargs"), [
    (8, {"task_kwargs": {"goal_radius": 3.0, "heading_tolerance_deg": 90}}),
    # any heading counts, so every path is checked against the goal disk: the batch's cheap
    # near-goal screen must never drop an arrival the lone robot's exact test finds
    *((16, {"backend": backend, "angles": [45, 90, 135],
            "task_kwargs": {"goal_radius": 0.5, "heading_tolerance_deg": 180}})
      for backend in ("kinematic", "cell")),
])
def test_navigation_goals_are_reached_identically(n, kwargs):
    """Terminations by the task (not only by time): goal regions that are hit."""
    native, sync = _pair("bounce_gym/BounceNavigation-v0", n, **kwargs)
    native.reset(seed=0)
    sync.reset(seed=0)
    native.action_space.seed(0)
    hits = 0
    for t in range(100):
        actions = native.action_space.sample()
        out, ref = native.step(actions), sync.step(actions)
        _same_step(out, ref, t)
        hits += int(out[2].sum())
    assert hits > 0


@pytest.mark.parametrize("backend", ["kinematic", "cell"])
@pytest.mark.parametrize("reward", [{"reward": "progress", "gamma": 0.9},
                                    {"reward": "sparse", "tick_cost": 0.01},
                                    {"reward": "plan_cost"}], ids=repr)
def test_every_navigation_reward_is_batched_identically(reward, backend):
    """Each ``reward`` option (the default, progress with γ = 1, runs in the tests above):
    the same rewards, ``plan_cost`` infos and terminations as N single envs."""
    native, sync = _pair("bounce_gym/BounceNavigation-v0", 8, max_episode_steps=50,
                         backend=backend, task_kwargs={"goal_radius": 1.5,
                                                       "heading_tolerance_deg": 90, **reward})
    a, b = native.reset(seed=21), sync.reset(seed=21)
    _same_infos(a[1], b[1], "reset")
    native.action_space.seed(3)
    hits = 0
    for t in range(120):
        actions = native.action_space.sample()
        out, ref = native.step(actions), sync.step(actions)
        _same_step(out, ref, t)
        hits += int(out[2].sum())
    assert hits > 0


def test_history_and_privileged_observations():
    native, sync = _pair("bounce_gym/Bounce-v0", 4, history=3, privileged=True)
    native.reset(seed=1)
    sync.reset(seed=1)
    for t in range(20):
        actions = np.array([t % 3, 1, 2, 0])
        _same_step(native.step(actions), sync.step(actions), t)


def test_vector_env_api():
    env = gym.make_vec("bounce_gym/Bounce-v0", num_envs=3)
    assert isinstance(env.unwrapped, BounceVectorEnv)
    assert env.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert env.num_envs == 3
    assert env.single_action_space == gym.spaces.Discrete(3)
    assert env.action_space == gym.spaces.MultiDiscrete([3, 3, 3])
    obs, info = env.reset(seed=0)
    assert obs in env.observation_space and obs.shape == (3, 1)  # the clock (bounce mode)
    assert info["_ticks"].all()
    obs2, _ = env.reset(seed=0)
    assert np.array_equal(obs, obs2)  # seeding is deterministic
    obs, rewards, terminated, truncated, info = env.step(env.action_space.sample())
    assert obs in env.observation_space
    assert rewards.dtype == np.float64 and terminated.dtype == truncated.dtype == np.bool_
    assert env.unwrapped.max_episode_steps == 500  # the registered limit


def test_reset_mask_resets_only_those_envs():
    env = BounceVectorEnv(3)
    obs, _ = env.reset(seed=4)
    moved, _, _, _, _ = env.step(np.array([0, 1, 2]))
    again, info = env.reset(options={"reset_mask": np.array([True, False, False])})
    assert np.array_equal(again[1:], moved[1:])
    assert info["_ticks"].tolist() == [True, False, False]


def test_pickling_keeps_the_episodes():
    env = BounceVectorEnv(4, world="lab_fig1", task="coverage")
    env.reset(seed=3)
    env.step(np.array([0, 1, 2, 0]))
    copy = pickle.loads(pickle.dumps(env))
    actions = np.array([2, 2, 1, 0])
    a, b = env.step(actions), copy.step(actions)
    for x, y in zip(a[:4], b[:4], strict=True):
        assert np.array_equal(x, y)


@pytest.mark.parametrize(("kwargs", "actions"), [
    ({}, np.array([0, 3])),
    ({}, np.array([0.0, 1.0])),
    ({}, np.array([0])),
    ({}, np.array([-1, 0])),
    ({"action_type": "continuous"}, np.array([[0.5], [1.5]], dtype=np.float32)),
    ({"action_type": "continuous"}, np.array([[np.nan], [0.0]])),
    ({"action_type": "continuous"}, np.array([[True], [False]])),
    ({"action_type": "continuous"}, np.zeros((2, 2))),
])
def test_bad_actions_raise_action_error(kwargs, actions):
    env = BounceVectorEnv(2, **kwargs)
    env.reset(seed=0)
    with pytest.raises(ActionError):
        env.step(actions)


@pytest.mark.parametrize(("kwargs", "reason"), [
    ({"step_mode": "tick"}, "tick"),
    ({"backend": "pymunk", "physics": "ideal"}, "pymunk"),
    ({"backend": "pymunk"}, "physics 'dynamic'"),
    ({"noise": {"type": "interval", "lo_deg": -5, "hi_deg": 5}}, "noise"),
    ({"world": "lab_localization_a", "task": "localization", "angles": (45.0,),
      "backend": "cell", "task_kwargs": {"filter_factory": "combinatorial"}}, "filter"),
    ({"render_mode": "rgb_array"}, "render"),
])
def test_what_is_not_batched_is_a_config_error(kwargs, reason):
    with pytest.raises(ConfigError, match=reason):
        BounceVectorEnv(2, **kwargs)


def test_localization_keeps_the_sync_fallback():
    env = gym.make_vec("bounce_gym/BounceLocalization-v0", num_envs=2)
    assert isinstance(env, gym.vector.SyncVectorEnv)


def test_returned_arrays_are_not_the_env_state():
    """Observations and infos may be kept and written by the caller without changing the
    episodes (the info arrays are handed out without a zero-filled copy)."""
    env, ref = BounceVectorEnv(3), BounceVectorEnv(3)
    env.reset(seed=2)
    ref.reset(seed=2)
    for t in range(30):
        actions = np.array([t % 3, 1, 2])
        out, expect = env.step(actions), ref.step(actions)
        _same_step(out, expect, t)
        for array in (out[0], *(v for k, v in out[4].items() if not k.startswith("_"))):
            array[...] = 0


@pytest.mark.parametrize(("task_kwargs", "options"), [
    # reset options: the first episodes are placed from the single core's draws, the autoreset
    # ones from random cells drawn by the batch
    ({}, {"start": {"position": [0.5, 0.5], "heading": 0.0},
          "goal": {"position": [8.5, 4.5], "heading": np.pi / 2}}),
    # a fixed goal: every episode draws only its start, through the single core
    ({"goal": {"position": [8.5, 4.5], "heading": np.pi / 2}}, None),
])
def test_cell_navigation_episodes_drawn_either_way(task_kwargs, options):
    native, sync = _pair("bounce_gym/BounceNavigation-v0", 6, max_episode_steps=30,
                         backend="cell", angles=[45, 90, 135],
                         task_kwargs={"goal_radius": 1.0, "heading_tolerance_deg": 90,
                                      **task_kwargs})
    a, b = native.reset(seed=7, options=options), sync.reset(seed=7, options=options)
    assert np.array_equal(a[0], b[0])
    _same_infos(a[1], b[1], "reset")
    assert _steps_alike(native, sync, 80, action_seed=4) >= 6  # every env autoreset


def test_the_batched_env_uses_only_public_members_of_other_objects():
    """`BounceVectorEnv`, its batched tasks, `GoalTables` and `CellRobots` read no private field of another object and assign
    no attribute of the single env, its core, its task or the backend (``single.goal = …`` was
    one)."""
    import ast
    from pathlib import Path

    import bounce_gym.envs.goal_tables as tables_module
    import bounce_gym.envs.vector_cells as cells_module
    import bounce_gym.envs.vector_env as env_module
    import bounce_gym.envs.vector_tasks as tasks_module

    for module in (env_module, cells_module, tasks_module, tables_module):
        tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr.startswith("_") \
                    and not node.attr.startswith("__"):
                base = node.value
                assert isinstance(base, ast.Name) and base.id in ("self", "cls"), \
                    f"{module.__name__}:{node.lineno} reads private {node.attr!r}"
            if isinstance(node, ast.Assign | ast.AugAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    if isinstance(target, ast.Attribute):
                        owners = set(ast.unparse(target).split(".")[:-1])  # whose field
                        assert not owners & {"single", "core", "task", "backend", "dynamics"}, \
                            f"{module.__name__}:{node.lineno} assigns {ast.unparse(target)}"


@pytest.mark.parametrize("tables", [True, False], ids=["goal tables", "per-env tests"])
@pytest.mark.parametrize("goal", [
    None,  # random cells: every goal a cell, tested by lookup when the tables fit
    {"position": [8.5, 4.5], "heading": np.pi / 2},  # a cell given as an option
    {"position": [8.3, 4.6], "heading": 1.0},  # no cell: the exact test of a lone robot
], ids=["drawn", "cell option", "off-cell option"])
def test_goal_tables_and_per_env_tests_agree_with_sync(goal, tables, monkeypatch):
    """Arrival and Φ by `GoalTables` lookups, and by the per-env tests of a map whose tables do
    not fit (`MAX_ENTRIES` 0), give the single env's rewards, terminations and infos; goals
    given as reset options are placed by the single core, autoreset ones drawn as cells."""
    import bounce_gym.envs.goal_tables as goal_tables

    if not tables:
        monkeypatch.setattr(goal_tables, "MAX_ENTRIES", 0)
    native, sync = _pair("bounce_gym/BounceNavigation-v0", 12, max_episode_steps=25,
                         backend="cell", angles=[45, 90, 135],
                         task_kwargs={"goal_radius": 1.2, "heading_tolerance_deg": 60})
    assert (native.unwrapped.task.tables is not None) == tables
    options = None if goal is None else {"goal": goal}
    a, b = native.reset(seed=3, options=options), sync.reset(seed=3, options=options)
    assert np.array_equal(a[0], b[0])
    _same_infos(a[1], b[1], "reset")
    if tables:  # only the off-cell goal leaves the lookups
        assert len(native.unwrapped.task.off_cell) == (12 if goal and goal["heading"] == 1.0
                                                       else 0)
    native.action_space.seed(5)
    first_hits = hits = 0
    for t in range(90):
        actions = native.action_space.sample()
        out = native.step(actions)
        _same_step(out, sync.step(actions), t)
        hits += int(out[2].sum())
        first_hits += int(out[2].sum()) if t < 25 else 0  # the episodes of the reset's goal
    assert first_hits > 0 and hits > first_hits
