"""The multi-robot PettingZoo environment: the official test kit plus our own checks."""

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
    seed_test,
    state_test,
)

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.envs import multi_bounce_v0
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv
from bounce_gym.errors import ActionError, ConfigError

VARIANTS = [
    dict(),
    dict(backend="pymunk", physics="ideal"),
    dict(backend="pymunk"),  # physics="dynamic"
    dict(backend="pymunk", task="coverage", step_mode="tick", turn_angles=[45, -45]),
    dict(backend="pymunk", world="grid_20x12", task="monitoring", angles=[[90], [135], [45, 90],
                                                                          [120]]),
    dict(action_type="continuous", step_mode="tick", history=2, privileged=True),
    dict(task="coverage", n_robots=3, robot_collisions="ignore", robot_radius=0.0),
    dict(world="grid_20x12", task="monitoring", angles=[[90], [135], [45, 90], [120]]),
    dict(backend="cell", world="grid_15x15", task="monitoring", n_robots=2, agent_id=True,
         step_mode="tick", task_kwargs={"observe_region": True}),
]


@pytest.fixture(autouse=True)
def _quiet_unknown_option_warnings():
    # parallel_api_test resets with options={"options": 1}; the env warns about the unknown key
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="reset options: unknown keys")
        yield


@pytest.mark.parametrize("kwargs", VARIANTS)
def test_parallel_api(kwargs):
    parallel_api_test(multi_bounce_v0.parallel_env(**kwargs), num_cycles=200)


@pytest.mark.parametrize("kwargs", [v for v in VARIANTS if v.get("step_mode") != "tick"])
def test_aec_api(kwargs):
    api_test(multi_bounce_v0.env(**kwargs), num_cycles=200)


NOISY = {"type": "reliable", "r": 0.5, "eps": 0.2}


@pytest.mark.parametrize("kwargs", [dict(), dict(backend="pymunk", physics="ideal", noise=NOISY),
                                    dict(backend="pymunk", noise=NOISY)])
def test_seed_tests(kwargs):
    seed_test(lambda **kw: multi_bounce_v0.env(**kwargs, **kw), num_cycles=100)


@pytest.mark.parametrize("kwargs", [dict(), dict(backend="pymunk", noise=NOISY)])
def test_parallel_seed_test(kwargs):
    parallel_seed_test(lambda **kw: multi_bounce_v0.parallel_env(**kwargs, **kw))


def test_max_cycles():
    max_cycles_test(multi_bounce_v0)


def test_render_modes():
    render_test(multi_bounce_v0.env)
    env = multi_bounce_v0.parallel_env(render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3


def test_state_space():
    state_test(multi_bounce_v0.env(), multi_bounce_v0.parallel_env())


def _rollout(env, seed, n_steps):
    obs, infos = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = [(obs, infos)]
    for _ in range(n_steps):
        actions = {a: int(rng.integers(env.action_space(a).n)) for a in env.agents}
        out.append(env.step(actions))
        if not env.agents:
            break
    return out


@pytest.mark.parametrize("backend", [dict(backend="kinematic"),
                                     dict(backend="pymunk", physics="ideal"),
                                     dict(backend="pymunk")], ids=["kinematic", "ideal", "dynamic"])
def test_multi_step_parallel_determinism(backend):
    """The released parallel_seed_test checks one step only (PettingZoo #1437): check 250."""
    kwargs = dict(**backend, n_robots=5, noise={"type": "reliable", "r": 0.7, "eps": 0.3},
                  task="coverage", max_cycles=250)
    a = _rollout(MultiBounceEnv(**kwargs), 3, 250)
    b = _rollout(MultiBounceEnv(**kwargs), 3, 250)
    assert len(a) == len(b) == 251
    assert data_equivalence(a, b, exact=True)
    c = _rollout(MultiBounceEnv(**kwargs), 4, 250)
    assert not data_equivalence(a, c, exact=True)


@pytest.mark.parametrize("physics", ["ideal", "dynamic"])
def test_pickle_mid_episode_continues_identically(physics):
    """Colliding robots too: the dynamic model's rebuilt space continues bit for bit."""
    env = MultiBounceEnv(n_robots=4, backend="pymunk", physics=physics, task="coverage",
                         noise={"type": "interval", "lo": -0.1, "hi": 0.1})
    env.reset(seed=5)
    for _ in range(20):
        env.step(dict.fromkeys(env.agents, 1))
    twin = pickle.loads(pickle.dumps(env))
    for k in range(100):
        actions = {a: (k + i) % 3 for i, a in enumerate(env.agents)}
        assert data_equivalence(env.step(actions), twin.step(actions), exact=True)


def test_aec_is_event_driven():
    env = MultiBounceAEC(n_robots=4, max_cycles=30)
    env.reset(seed=2)
    seen = 0
    for agent in env.agent_iter():
        obs, reward, term, trunc, info = env.last()
        if term or trunc:
            env.step(None)
            continue
        i = env.agent_index[agent]
        assert env.core.state.blocked[i], "only a robot that is bumping gets to act"
        assert obs[0] == 1.0  # its contact sensor is pressed
        env.step(seen % 3)
        seen += 1
    assert seen == 4 * 30


def test_head_on_robots_both_bump_and_contacts_are_reported():
    env = MultiBounceEnv(world="square", n_robots=2, robot_radius=0.5, angles=[90])
    start = {"position": [[2, 5], [8, 5]], "heading": [0.0, np.pi]}
    obs, infos = env.reset(seed=0, options={"start": start})
    assert infos["robot_0"]["contact_robot"] == 1 and infos["robot_1"]["contact_robot"] == 0
    np.testing.assert_allclose(infos["robot_0"]["position"], [4.5, 5])
    assert obs["robot_0"][0] == obs["robot_1"][0] == 1.0
    _, _, _, _, infos = env.step({"robot_0": 0, "robot_1": 0})
    assert infos["robot_0"]["bumps"] >= 1 and infos["robot_1"]["bumps"] >= 1


def test_monitoring_rewards_time_in_own_region_and_penalises_contacts():
    env = MultiBounceEnv(world="rectangle", n_robots=2, task="monitoring", robot_radius=0.5,
                         angles=[90], task_kwargs={"contact_penalty": 2.0})
    start = {"position": [[3, 5], [17, 5]], "heading": [np.pi / 2, np.pi / 2]}
    env.reset(seed=0, options={"start": start})
    _, rewards, _, _, infos = env.step({"robot_0": 0, "robot_1": 0})
    # both drive along x = const inside their own half of the rectangle
    # (robot 0 reaches the wall mid-tick and stands there, in its region, until the step ends)
    assert rewards == {"robot_0": pytest.approx(1.0), "robot_1": pytest.approx(1.0)}
    head_on = {"position": [[4, 5], [16, 5]], "heading": [0.0, np.pi]}
    env.reset(seed=0, options={"start": head_on})
    _, rewards, _, _, infos = env.step({"robot_0": 0, "robot_1": 0})
    assert infos["robot_0"]["robot_contacts"] == 0


def test_coverage_is_shared_and_grows():
    env = MultiBounceEnv(n_robots=4, task="coverage", max_cycles=300)
    env.reset(seed=1)
    first = None
    for _ in range(300):
        *_, infos = env.step(dict.fromkeys(env.agents, 2))
        first = first if first is not None else infos["robot_0"]["coverage"]
        if not env.agents:
            break
    last = infos["robot_0"]["coverage"]
    assert last > first and all(i["coverage"] == last for i in infos.values())


def test_registry_and_old_style_module():
    par = pettingzoo.make("parallel", "bounce_gym/MultiBounceCoverage-v0", n_robots=2)
    aec = pettingzoo.make("aec", "bounce_gym/MultiBounce-v0", n_robots=2)
    assert par.possible_agents == ["robot_0", "robot_1"] and par.max_cycles == 500
    aec.reset(seed=0)
    assert aec.agent_selection in aec.possible_agents


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(n_robots=0), "n_robots"),
        (dict(task="navigation"), "task"),
        (dict(robot_collisions="push"), "robot_collisions"),
        (dict(robot_radius=0.0), "robot_radius > 0"),
        (dict(max_cycles=0), "max_cycles"),
        (dict(angles=[[90], [45]]), "2 angle sets for 4 robots"),
        (dict(angles={"robot_0": [90]}), "dict keys"),
        (dict(render_mode="video"), "render_mode"),
        (dict(world="atlantis"), "world"),
        (dict(task="monitoring", task_kwargs={"regions": [[(0, 0), (1, 0), (0, 1)]]}), "regions"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        MultiBounceEnv(**kwargs)


def test_aec_rejects_tick_mode_and_bad_actions():
    with pytest.raises(ConfigError, match="event-driven"):
        MultiBounceAEC(step_mode="tick")
    env = MultiBounceEnv(n_robots=2)
    env.reset(seed=0)
    with pytest.raises(ActionError, match="missing"):
        env.step({"robot_0": 0})
    with pytest.raises(ActionError, match="out of range"):
        env.step({"robot_0": 0, "robot_1": 7})
    with pytest.raises(ActionError, match="dict"):
        env.step([0, 1])


def test_path_samples_account_for_every_tick():
    from bounce_gym.envs.tasks.base import StepEvents, path_samples

    events = StepEvents(ticks=4, start=np.array([[3.0, 9.5], [17.0, 9.5]]),
                        end=np.array([[0.5, 9.5], [14.0, 9.5]]), heading=np.array([np.pi, np.pi]),
                        bumps=np.array([1, 1]), angles=np.array([1.0, 1.0]),
                        angle_changed=np.array([False, False]),
                        robot_contact=np.array([False, False]))
    robot, points, ticks = path_samples(events, step_length=1.0, spacing=0.25)
    np.testing.assert_allclose(np.bincount(robot, weights=ticks), [4.0, 4.0])
    # robot 0 drove 2.5 ticks, bumped 1 and stood 0.5 at its end point
    at_end = (robot == 0) & np.all(points == [0.5, 9.5], axis=1)
    assert ticks[at_end].sum() == pytest.approx(0.5)


def test_agent_infos_hold_each_robots_own_row_and_do_not_share_memory():
    env = MultiBounceEnv(n_robots=5, task="monitoring")
    env.reset(seed=1)
    *_, infos = env.step(dict.fromkeys(env.agents, 1))
    state = env.core.state
    for agent, info in infos.items():
        i = env.agent_index[agent]
        np.testing.assert_array_equal(info["position"], state.position[i])
        assert info["position"].shape == (2,) and info["cell"].shape == (2,)
        assert isinstance(info["heading"], np.float64) and info["heading"] == state.heading[i]
        for key in ("clock", "bumps", "contact_edge", "contact_robot"):
            assert isinstance(info[key], np.int64) and info[key] == getattr(state, key)[i]
        assert info["encounters"] == infos["robot_0"]["encounters"]  # shared entries
    before = state.position.copy()
    infos["robot_0"]["position"][:] = -1.0
    np.testing.assert_array_equal(state.position, before)
    assert infos["robot_1"]["position"][0] != -1.0


def test_a_team_observation_carries_the_robot_id_and_its_region():
    """``agent_id``: robot i's observation ends with the one-hot of i (before the task's
    features); monitoring's ``observe_region``: then its region's bounds scaled to [-1, 1]."""
    env = multi_bounce_v0.parallel_env(backend="cell", world="grid_15x15", task="monitoring",
                                       n_robots=2, step_mode="tick", agent_id=True,
                                       task_kwargs={"observe_region": True, "regions": [
                                           [[0, 0], [7.5, 0], [7.5, 15], [0, 15]],
                                           [[7.5, 0], [15, 0], [15, 15], [7.5, 15]]]})
    obs, _ = env.reset(seed=3)
    assert env.observation_space("robot_0").shape == (2 + 2 + 4,)
    np.testing.assert_array_equal(obs["robot_0"][2:], [1, 0, -1, -1, 0, 1])
    np.testing.assert_array_equal(obs["robot_1"][2:], [0, 1, 0, -1, 1, 1])
    for _ in range(20):
        obs, *_ = env.step(dict.fromkeys(env.agents, 0))
        assert all(env.observation_space(a).contains(o) for a, o in obs.items())
        np.testing.assert_array_equal(obs["robot_1"][2:4], [0, 1])
    blind = multi_bounce_v0.parallel_env(backend="cell", world="grid_15x15", task="monitoring",
                                         n_robots=2, step_mode="tick")
    assert blind.observation_space("robot_0").shape == (2,)
    assert blind.reset(seed=3)[0]["robot_0"].tolist() == obs_at_reset(env, 3)["robot_0"][:2]


def obs_at_reset(env, seed):
    return {a: o.tolist() for a, o in env.reset(seed=seed)[0].items()}


def test_agent_id_needs_several_robots():
    with pytest.raises(ConfigError, match="^agent_id: a lone robot"):
        multi_bounce_v0.parallel_env(n_robots=1, agent_id=True)
