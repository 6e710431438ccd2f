"""`TeamVectorEnv` against B separate `MultiBounceEnv` stepped with the same actions."""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym.envs.multi_bounce_env import PER_ROBOT_INFO, MultiBounceEnv
from bounce_gym.envs.tasks import MonitoringTask
from bounce_gym.envs.team_vector_env import TeamVectorEnv
from bounce_gym.errors import ActionError, ConfigError

HALVES = [[[0, 0], [7.5, 0], [7.5, 15], [0, 15]], [[7.5, 0], [15, 0], [15, 15], [7.5, 15]]]
#: configs/benchmark.yaml's cell-backend multi-robot configurations
COVERAGE = {"world": "grid_10x10", "task": "coverage", "n_robots": 3, "backend": "cell",
            "step_mode": "tick", "angles": [45, 90, 135], "corner_rule": "no_squeeze",
            "robot_collisions": "bounce", "turn_angles": [45, -45]}
MONITORING = {"world": "grid_15x15", "task": "monitoring", "n_robots": 2, "backend": "cell",
              "step_mode": "tick", "angles": [45, 90, 135], "corner_rule": "no_squeeze",
              "robot_collisions": "ignore", "task_kwargs": {"regions": HALVES}}
CASES = {
    "coverage benchmark": COVERAGE,
    "monitoring benchmark": MONITORING,
    "min_sep_cells 1": {**COVERAGE, "n_robots": 4, "min_sep_cells": 1,
                        "corner_rule": "target_only"},
    # robots that collide in monitoring (contact penalties), each with its own angles, with the
    # history and the privileged pose in the observation
    "per-robot angles": {**MONITORING, "n_robots": 3, "robot_collisions": "bounce",
                         "angles": [[45, 90, 135], [90], [135, 225]], "turn_angles": [90],
                         "task_kwargs": None, "history": 3, "privileged": True},
    "agent_id, observe_region": {**MONITORING, "agent_id": True,
                                 "task_kwargs": {"regions": HALVES, "observe_region": True}},
    "free": {"world": "grid_15x15", "n_robots": 4, "backend": "cell", "step_mode": "tick",
             "robot_collisions": "bounce", "history": 2},
}
B = 5


class OwnMonitoring(MonitoringTask):
    """A task of the user's own (here: monitoring unchanged), which the batch cannot know."""


def _same(mine, theirs, where) -> None:
    mine, theirs = np.asarray(mine), np.asarray(theirs)
    assert mine.dtype.kind == theirs.dtype.kind and np.array_equal(mine, theirs), \
        (where, mine, theirs)


def _same_as_envs(obs, infos, expected, agents, where) -> None:
    """Team i's observations and infos against env i's (``expected``: (obs, infos) dicts)."""
    for i, (their_obs, their_infos) in enumerate(expected):
        for j, agent in enumerate(agents):
            assert obs[i, j].dtype == their_obs[agent].dtype
            _same(obs[i, j], their_obs[agent], (where, i, agent, "obs"))
            for key, value in their_infos[agent].items():
                _same(infos[key][i, j] if key in PER_ROBOT_INFO else infos[key][i], value,
                      (where, i, agent, key))


@pytest.mark.parametrize("kwargs", CASES.values(), ids=CASES.keys())
def test_same_episodes_as_separate_pettingzoo_envs(kwargs):
    """Same seeds and actions: identical observations, rewards, flags, infos and states, across
    four truncations and next-step autoresets."""
    max_cycles, steps = 70, 300
    batch = TeamVectorEnv(B, max_cycles=max_cycles, **kwargs)
    envs = [MultiBounceEnv(max_cycles=max_cycles, **kwargs) for _ in range(B)]
    agents = envs[0].possible_agents
    obs, infos = batch.reset(seed=7)
    assert obs in batch.observation_space
    _same_as_envs(obs, infos, [env.reset(seed=7 + i) for i, env in enumerate(envs)], agents,
                  "reset")
    rng = np.random.default_rng(1)
    resets = contacts = encounters = 0
    autoreset = False
    for t in range(steps):
        actions = (rng.random((B, len(agents))) * batch.cells.n_choices).astype(np.int64)
        obs, rewards, terminated, truncated, infos = batch.step(actions)
        if autoreset:  # NEXT_STEP: this step reset every team, its actions unused
            _same_as_envs(obs, infos, [env.reset() for env in envs], agents, t)
            assert not (rewards.any() or terminated.any() or truncated.any())
            resets += 1
            autoreset = False
            continue
        expected = []
        for i, env in enumerate(envs):
            out = env.step({a: int(actions[i, j]) for j, a in enumerate(agents)})
            expected.append((out[0], out[4]))
            for j, agent in enumerate(agents):
                assert rewards[i, j] == out[1][agent], (t, i, agent)
                assert terminated[i, j] == out[2][agent] and truncated[i, j] == out[3][agent]
            _same(batch.state()[i], env.state(), (t, i, "state"))
        _same_as_envs(obs, infos, expected, agents, t)
        autoreset = bool(truncated.all())
        contacts += int((infos["contact_robot"] >= 0).sum())
        encounters += int(infos.get("encounters", np.zeros(1)).sum())
    assert resets == steps // (max_cycles + 1)
    if kwargs.get("robot_collisions") == "bounce":
        assert contacts > 0  # the conflict rules were exercised
    elif kwargs.get("task") == "monitoring":
        assert encounters > 0  # robots that ignore each other shared cells


@pytest.mark.parametrize(("kwargs", "reason"), [
    ({"backend": "kinematic"}, "backend 'kinematic'"),
    ({"step_mode": "bounce"}, "step_mode 'bounce'"),
    ({"noise": {"type": "reliable", "r": 0.9, "eps_deg": 45}}, "noise"),
    ({"render_mode": "rgb_array"}, "render_mode"),
    ({"task": OwnMonitoring()}, "task OwnMonitoring"),
])
def test_what_is_not_batched_is_a_one_line_config_error(kwargs, reason):
    with pytest.raises(ConfigError, match=reason) as error:
        TeamVectorEnv(2, **{**MONITORING, "task_kwargs": None, **kwargs})
    message = str(error.value)
    assert "\n" not in message and "PettingZoo env" in message


@pytest.mark.parametrize("actions", [
    np.zeros((B, 3), dtype=np.int64),  # the wrong number of robots
    np.zeros((B, 2)),  # not integers
    np.array([[0, 3]] * B),  # past robot 1's 3 angles
    np.array([[-1, 0]] * B),
])
def test_bad_actions_raise_action_error(actions):
    batch = TeamVectorEnv(B, **MONITORING)
    batch.reset(seed=0)
    with pytest.raises(ActionError):
        batch.step(actions)


def test_team_vector_env_api():
    batch = TeamVectorEnv(3, **COVERAGE)
    with pytest.raises(ConfigError, match="before reset"):
        batch.step(np.zeros((3, 3), dtype=np.int64))
    assert batch.metadata["autoreset_mode"].value == "NextStep"
    assert batch.max_cycles == 500  # the PettingZoo env's default
    assert batch.action_space.shape == (3, 3) and batch.action_space.nvec.max() == 5
    obs, _ = batch.reset(seed=2)
    again, _ = batch.reset(seed=2)
    assert np.array_equal(obs, again)  # seeding is deterministic
    assert obs.shape == (3, 3, 2) and batch.single_observation_space.shape == (2,)
    obs, rewards, terminated, truncated, infos = batch.step(batch.action_space.sample())
    assert obs in batch.observation_space and batch.state().shape == (3, 12)
    assert rewards.dtype == np.float64 and terminated.dtype == truncated.dtype == np.bool_
    assert infos["coverage"].shape == (3,) and infos["position"].shape == (3, 3, 2)


def test_the_team_env_uses_only_public_members_of_other_objects():
    """The team modules read no private field of another object and assign no attribute of
    the single env, its core, its task, the backend or the dynamics."""
    import ast
    from pathlib import Path

    import bounce_gym.envs.team_cells as cells_module
    import bounce_gym.envs.team_tasks as tasks_module
    import bounce_gym.envs.team_vector_env as env_module

    for module in (env_module, cells_module, tasks_module):
        tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr.startswith("_") \
                    and not node.attr.startswith("__"):
                assert isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"), \
                    f"{module.__name__}:{node.lineno} reads private {node.attr!r}"
            if isinstance(node, ast.Assign | ast.AugAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    if isinstance(target, ast.Attribute):
                        owners = set(ast.unparse(target).split(".")[:-1])
                        assert not owners & {"single", "core", "task", "backend", "dynamics"}, \
                            f"{module.__name__}:{node.lineno} assigns {ast.unparse(target)}"
