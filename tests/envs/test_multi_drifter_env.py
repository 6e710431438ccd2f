"""`bounce_gym/MultiDrifter-v0`: PettingZoo's test kit (parallel, AEC through parallel_to_aec,
seeds, render, state), deployment, shared surface coverage, seeding and pickling."""

import pickle
import warnings

import numpy as np
import pettingzoo
import pytest
from gymnasium.utils.env_checker import data_equivalence
from pettingzoo.test import (
    api_test,
    max_cycles_test,
    parallel_api_test,
    parallel_seed_test,
    render_test,
    state_test,
)

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.cells import DOWN, DRIFT
from bounce_gym.envs.drifters import multi_drifter_v0
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv
from bounce_gym.errors import ActionError, ConfigError

THREE = dict(flow="two_sink", flow_kwargs={"n_layers": 3})
VARIANTS = [
    dict(),
    dict(THREE, n_drifters=3, observe_fix=True, observe_pose=True),
    dict(THREE, backend="continuous", diffusivity=20.0, n_drifters=2),
]


@pytest.fixture(autouse=True)
def _quiet_test_kit_warnings():
    # parallel_api_test resets with options={"options": 1} (the env warns about the unknown
    # key); an observation at reset is all zeros (surface, clock 0), which api_test notes
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="reset options: unknown keys")
        warnings.filterwarnings("ignore", message="Observation numpy array is all zeros")
        yield


@pytest.mark.parametrize("kwargs", VARIANTS)
def test_parallel_api(kwargs):
    parallel_api_test(multi_drifter_v0.parallel_env(**kwargs), num_cycles=100)


@pytest.mark.parametrize("kwargs", VARIANTS)
def test_aec_api(kwargs):
    api_test(multi_drifter_v0.env(**kwargs), num_cycles=60)


@pytest.mark.parametrize("kwargs", [THREE, dict(THREE, backend="continuous", diffusivity=50.0)],
                         ids=["cell", "continuous"])
def test_parallel_seed_test(kwargs):
    parallel_seed_test(lambda: multi_drifter_v0.parallel_env(**kwargs), num_cycles=50)


def test_max_cycles_render_and_state():
    max_cycles_test(multi_drifter_v0)
    render_test(lambda render_mode=None: multi_drifter_v0.env(render_mode=render_mode, **THREE))
    state_test(multi_drifter_v0.env(**THREE), multi_drifter_v0.parallel_env(**THREE))


def test_registered_ids():
    parallel = pettingzoo.make("parallel", "bounce_gym/MultiDrifter-v0", max_cycles=7)
    assert isinstance(parallel, MultiDrifterEnv) and parallel.max_cycles == 7
    aec = pettingzoo.make("aec", "bounce_gym/MultiDrifter-v0", n_drifters=2)
    aec.reset(seed=0)
    assert aec.agents == ["drifter_0", "drifter_1"]


def test_deployment_and_shared_coverage_reward():
    env = MultiDrifterEnv(**THREE, n_drifters=3,
                          deploy=[(0, 2, 2), {"cell": (0, 15, 5), "halo": 0}, (1, 10, 10)])
    _, infos = env.reset(seed=0)
    cells = [tuple(infos[a]["cell"].tolist()) for a in env.agents]
    assert cells == [(0, 2, 2), (0, 15, 5), (1, 10, 10)]
    surface = 522
    assert infos["drifter_0"]["coverage"] == pytest.approx(2 / surface)  # two at the surface
    visited = {(2, 2), (15, 5)}
    for _ in range(30):
        _, rewards, _, _, infos = env.step(dict.fromkeys(env.agents, DRIFT))
        new = {tuple(infos[a]["cell"][1:].tolist()) for a in env.agents
               if infos[a]["layer"] == 0} - visited
        visited |= new
        assert infos["drifter_0"]["new_cells"] == len(new)
        assert all(r == pytest.approx(len(new) / 3) for r in rewards.values())
    assert infos["drifter_1"]["coverage"] == pytest.approx(len(visited) / surface)


def test_deep_drifters_do_not_cover_the_surface():
    env = MultiDrifterEnv(**THREE, n_drifters=2, deploy=[(0, 10, 3), (0, 10, 20)])
    env.reset(seed=0)
    _, rewards, *_ , infos = env.step(dict.fromkeys(env.agents, DOWN))
    assert rewards == {"drifter_0": 0.0, "drifter_1": 0.0}
    coverage = infos["drifter_0"]["coverage"]
    for _ in range(10):
        _, rewards, *_ , infos = env.step(dict.fromkeys(env.agents, DRIFT))
        assert sum(rewards.values()) == 0.0
    assert infos["drifter_0"]["coverage"] == coverage


def test_the_fleet_size_follows_the_deploy_list():
    env = MultiDrifterEnv(**THREE, deploy=[(0, 1, 1), (1, 2, 2)])
    assert env.possible_agents == ["drifter_0", "drifter_1"]


def test_random_deployment_is_distinct_surface_cells():
    env = MultiDrifterEnv(**THREE, n_drifters=50)
    _, infos = env.reset(seed=4)
    cells = {tuple(info["cell"].tolist()) for info in infos.values()}
    assert len(cells) == 50 and all(c[0] == 0 for c in cells)


def test_illegal_moves_and_action_masks():
    env = MultiDrifterEnv(**THREE, n_drifters=2, deploy=[(0, 5, 5), (2, 5, 5)])
    _, infos = env.reset(seed=0)
    assert env.action_mask("drifter_0").tolist() == [1, 0, 1]
    assert infos["drifter_1"]["action_mask"].tolist() == [1, 1, 0]
    _, _, _, _, infos = env.step({"drifter_0": 1, "drifter_1": 2})  # both illegal: they drift
    assert infos["drifter_0"]["illegal_action"] and infos["drifter_1"]["illegal_action"]
    assert (infos["drifter_0"]["layer"], infos["drifter_1"]["layer"]) == (0, 2)


def test_pickled_env_continues_exactly():
    env = MultiDrifterEnv(**THREE, backend="continuous", diffusivity=30.0, n_drifters=3)
    env.reset(seed=1)
    env.step(dict.fromkeys(env.agents, DOWN))
    clone = pickle.loads(pickle.dumps(env))
    rng = np.random.default_rng(2)
    for _ in range(20):
        actions = {a: int(rng.integers(3)) for a in env.agents}
        assert data_equivalence(env.step(actions), clone.step(actions), exact=True)


@pytest.mark.parametrize(("kwargs", "field"), [
    (dict(n_drifters=0), "n_drifters"),
    (dict(n_drifters=2, deploy=[(0, 1, 1)]), "deploy"),
    (dict(deploy={"layer": 0}), "deploy"),
    (dict(n_drifters=2, deploy=[(0, 1, 1), (0, 20, 28)]), r"deploy\[1\]"),
    (dict(max_cycles=0), "max_cycles"),
    (dict(backend="continuous", land_rule="bounce"), "land_rule"),
])
def test_bad_arguments(kwargs, field):
    with pytest.raises(ConfigError, match=f"^{field}"):
        env = MultiDrifterEnv(**kwargs)
        env.reset(seed=0)


def test_single_drifter_arguments_are_refused():
    for name, value in (("task", "reach"), ("goal", (0, 1, 1)), ("start", (0, 1, 1))):
        with pytest.raises(TypeError, match=name):
            MultiDrifterEnv(**{name: value})


def test_bad_actions():
    env = MultiDrifterEnv(**THREE, n_drifters=2)
    env.reset(seed=0)
    with pytest.raises(ActionError, match="missing"):
        env.step({"drifter_0": 0})
    with pytest.raises(ActionError, match="action of drifter_1"):
        env.step({"drifter_0": 0, "drifter_1": 5})
    with pytest.raises(ConfigError, match="options.deploy"):
        env.reset(options={"deploy": [(0, 1, 1)]})
