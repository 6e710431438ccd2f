"""The seam between environments and planners: ``env.unwrapped.cell_model()``.

The env hands planners and tasks the discrete model it uses: the cell backend's own `CellModel`,
or on a continuous backend one built once from the env's options (cell size = step length, the
env's ``cell_bins`` and ``corner_rule``, the robot's radius).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym
from baselines.coverage.policy import MixturePolicy
from baselines.localization.policy import AngleSwitchPolicy
from baselines.multirobot.policies import CoveragePlanPolicy
from baselines.navigation.policy import NavigationPlanner
from bounce_gym.cells import CellModel
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError

ROOT = Path(__file__).parents[2]


@pytest.fixture
def count_models(monkeypatch):
    """The number of `CellModel`s built so far (a list, to be read after the calls)."""
    built = []
    original = CellModel.__init__

    def counting(self, *args, **kwargs):
        built.append(self)
        original(self, *args, **kwargs)

    monkeypatch.setattr(CellModel, "__init__", counting)
    return built


@pytest.mark.parametrize("env", [
    lambda: BounceEnv(world="square", backend="cell", angles=[90], cell_bins=4),
    lambda: MultiBounceEnv(world="grid_10x10", backend="cell", n_robots=2, angles=[90]),
])
def test_the_cell_backend_hands_out_its_own_model(env):
    env = env()
    model = env.cell_model()
    assert model is env.core.dynamics.backend.model
    # the model the robot steps is the answer whatever a planner asks for
    assert env.cell_model(360, "strict") is model


def test_a_continuous_backend_builds_one_model_per_discretisation_and_keeps_it(count_models):
    env = BounceEnv(world="two_rooms", robot_radius=0.2, step_length=0.5, cell_bins=4,
                    corner_rule="no_squeeze")
    model = env.cell_model()
    assert env.cell_model() is model and env.cell_model(4, "no_squeeze") is model
    assert len(count_models) == 1
    by_hand = CellModel(env.world, 0.5, 4, 0.2, "no_squeeze")
    for phi in (math.pi / 2, math.pi):
        for ours, theirs in zip(model.successor(phi), by_hand.successor(phi), strict=True):
            assert np.array_equal(ours, theirs)
    fine = env.cell_model(n_bins=8)
    assert fine is not model and fine.n_bins == 8 and fine.corner_rule == "no_squeeze"
    assert np.array_equal(fine.targets, CellModel(env.world, 0.5, 8, 0.2, "no_squeeze").targets)


def test_the_multi_robot_envs_default_to_their_own_options():
    env = MultiBounceEnv(n_robots=2)
    model = env.unwrapped.cell_model()
    assert (model.cell_size, model.n_bins, model.robot_radius, model.corner_rule) == (
        1.0, 8, 0.3, "target_only")


def test_cell_bins_and_corner_rule_are_checked_on_every_backend():
    with pytest.raises(ConfigError, match="cell_bins"):
        BounceEnv(cell_bins=7)
    with pytest.raises(ConfigError, match="corner_rule"):
        MultiBounceEnv(corner_rule="squeeze")


# -- the planners take the env's model -----------------------------------------------------------

def test_navigation_and_localization_planners_plan_on_the_env_model(count_models):
    env = gym.make("bounce_gym/BounceNavigation-v0", world="square")
    model = env.unwrapped.cell_model()
    planner = NavigationPlanner()
    env.reset(seed=0)
    planner.reset(env)
    assert planner.roadmap.model is model
    loc = gym.make("bounce_gym/BounceLocalization-v0", world="square", angles=[45, 90])
    policy = AngleSwitchPolicy.for_env(loc)
    assert policy.filter.model is loc.unwrapped.cell_model()
    assert loc.unwrapped.task.filter.model is loc.unwrapped.cell_model()
    assert len(count_models) == 2  # one per env, none by the planners


def test_the_coverage_mixture_and_multi_robot_planners_build_no_model(count_models):
    env = BounceEnv(world="square", angles=[90, 135])
    env.cell_model(n_bins=360)
    MixturePolicy.for_env(env)
    multi = MultiBounceEnv(world="grid_10x10", n_robots=2, step_mode="tick", angles=[135],
                           turn_angles=[45, -45])
    policy = CoveragePlanPolicy.for_env(multi)
    assert policy.joint_model.model is multi.cell_model(8, "no_squeeze")
    assert len(count_models) == 2


def test_no_planner_or_task_builds_a_cell_model_or_reads_the_dynamics():
    adapters = [*(ROOT / "baselines").rglob("polic*.py"), *(ROOT / "bounce_gym/envs/tasks").glob(
        "*.py")]
    for path in adapters:
        assert not re.search(r"\bCellModel\(", path.read_text(encoding="utf-8")), path
    for path in (ROOT / "baselines").rglob("*.py"):
        assert ".core.dynamics" not in path.read_text(encoding="utf-8"), path


def test_the_package_never_names_the_planners():
    package = Path(bounce_gym.__file__).parent
    for path in package.rglob("*"):
        if path.is_file() and "__pycache__" not in path.parts:
            # stable_baselines3: the third-party module `bounce_gym.extras` maps to its extra,
            # and stable-baselines3 its distribution, whose version `bounce_gym.provenance` records
            text = path.read_bytes().lower().replace(b"stable_baselines3", b"").replace(
                b"stable-baselines3", b"")
            assert b"baselines" not in text, path


# -- the localization task's built-in filter ----------------------------------------------------

def test_the_registered_localization_env_uses_the_combinatorial_filter():
    env = gym.make("bounce_gym/BounceLocalization-v0")
    task = env.unwrapped.task
    assert task.filter_factory == "combinatorial"
    _, info = env.reset(seed=0)
    assert "candidates" in info and "localized" in info


def test_a_bad_filter_factory_names_the_argument():
    with pytest.raises(ConfigError, match="filter_factory"):
        BounceEnv(task="localization", task_kwargs={"filter_factory": "no_such_module:f"})
    with pytest.raises(ConfigError, match="filter_factory"):
        BounceEnv(task="localization", task_kwargs={"filter_factory": 3})


def test_a_filter_factory_string_never_imports_or_calls_code(capsys):
    """A configuration file is data: ``"module:function"`` strings are refused, not run."""
    with pytest.raises(ConfigError, match="filter_factory: expected 'combinatorial', 'belief', "
                                          r"'particles', None or \(from Python\) a callable, "
                                          "got 'builtins:print'"):
        BounceEnv(task="localization", task_kwargs={"filter_factory": "builtins:print"})
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize("result", [None, 3, object()])
def test_a_filter_factory_must_return_a_filter(result):
    with pytest.raises(ConfigError, match="filter_factory: .* not a localization filter"):
        BounceEnv(task="localization", task_kwargs={"filter_factory": lambda options: result})
