"""`bounce_gym/Drifter-v0`: the Gymnasium checks, seeding and pickling, the cell backend against
the GCM's absorption probabilities, the continuous backend against `Drifters`, sensing, tasks and
argument errors."""

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.cells import DOWN, DRIFT, UP
from bounce_gym.dynamics import Drifters
from bounce_gym.envs.drifters.env import DrifterEnv
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.flows import get_flow, save_flow
from bounce_gym.markov.gcm import layer_gcm

#: three layers of the two-sink basin: small, static, with up and down moves everywhere
THREE = dict(flow="two_sink", flow_kwargs={"n_layers": 3})
VARIANTS = [
    dict(),
    dict(THREE, backend="continuous", observe_fix=True, observe_pose=True, diffusivity=20.0),
    dict(THREE, task="stay", region={"cell": (1, 10, 10), "halo": 2}),
    dict(THREE, task="cover", observe_fix=True),
    dict(backend="continuous", land_rule="slide", reward="thesis"),
]


@pytest.mark.parametrize("kwargs", VARIANTS)
def test_gymnasium_check_env(kwargs):
    env = gym.make("bounce_gym/Drifter-v0", **kwargs)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert [str(w.message) for w in rec] == []


def test_sb3_check_env_and_action_masks():
    from sb3_contrib.common.maskable.utils import get_action_masks, is_masking_supported
    from stable_baselines3.common.env_checker import check_env as sb3_check_env
    from stable_baselines3.common.env_util import make_vec_env

    sb3_check_env(DrifterEnv(**THREE), warn=True)
    vec = make_vec_env("bounce_gym/Drifter-v0", n_envs=2, seed=0, env_kwargs=THREE)
    assert is_masking_supported(vec)
    vec.reset()
    masks = get_action_masks(vec)
    assert masks.shape == (2, 3) and masks[:, DRIFT].all()
    # at the surface (every start is) there is no layer above
    assert not masks[:, UP].any()


def test_registered_horizon_truncates():
    env = gym.make("bounce_gym/Drifter-v0", **THREE, goal=(0, 6, 18))
    env.reset(seed=0, options={"start": (2, 0, 0)})  # far from the goal, on the bottom layer
    steps, truncated, terminated = 0, False, False
    while not (truncated or terminated):
        *_, terminated, truncated, _ = env.step(DRIFT)
        steps += 1
    assert truncated and steps == 200


# -- seeding and pickling --------------------------------------------------------------------
def _rollout(env, seed: int, n: int) -> list:
    out = [env.reset(seed=seed)]
    actions = np.random.default_rng(seed)
    for _ in range(n):
        step = env.step(int(actions.integers(3)))
        out.append(step)
        if step[2] or step[3]:
            out.append(env.reset())
    return out


@pytest.mark.parametrize("kwargs", [THREE, dict(THREE, backend="continuous", diffusivity=50.0)],
                         ids=["cell", "continuous"])
def test_same_seed_same_trajectory(kwargs):
    a = _rollout(gym.make("bounce_gym/Drifter-v0", **kwargs), 7, 120)
    b = _rollout(gym.make("bounce_gym/Drifter-v0", **kwargs), 7, 120)
    c = _rollout(gym.make("bounce_gym/Drifter-v0", **kwargs), 8, 120)
    assert data_equivalence(a, b, exact=True)
    assert not data_equivalence(a, c, exact=True)


@pytest.mark.parametrize("kwargs", [THREE, dict(THREE, backend="continuous", diffusivity=50.0)],
                         ids=["cell", "continuous"])
def test_pickled_env_continues_exactly(kwargs):
    env = gym.make("bounce_gym/Drifter-v0", **kwargs)
    env.reset(seed=3)
    for _ in range(5):
        env.step(DRIFT)
    clone = pickle.loads(pickle.dumps(env))
    actions = np.random.default_rng(4).integers(3, size=60)
    for a in actions:
        one, two = env.step(int(a)), clone.step(int(a))
        assert data_equivalence(one, two, exact=True)
        if one[2] or one[3]:
            assert data_equivalence(env.reset(seed=int(a)), clone.reset(seed=int(a)), exact=True)


# -- the cell backend is the GCM -------------------------------------------------------------
def _monte_carlo(env: DrifterEnv, policy, start, episodes: int, horizon: int) -> float:
    successes = 0
    env.reset(seed=11)
    for _ in range(episodes):
        _, info = env.reset(options={"start": start})
        for _ in range(horizon):
            _, _, terminated, _, info = env.step(int(policy[info["state"]]))
            if terminated:
                successes += 1
                break
    return successes / episodes


def _reach_within(model, policy, goal: np.ndarray, start: int, horizon: int) -> float:
    """Exact probability that the chain of ``policy`` hits ``goal`` within ``horizon`` steps."""
    drift, up, down = model.action_matrices()
    rows = [drift, up, down]
    n = model.n_states
    P = sum((rows[a].multiply(np.asarray(policy == a, dtype=float)[:, None])) for a in range(3))
    P = P.tocsr()
    p = np.zeros(n)
    p[start] = 1.0
    hit = 0.0
    for _ in range(horizon):
        p = P.T @ p
        hit += p[goal].sum()
        p[goal] = 0.0  # absorbed
    return hit


def test_cell_backend_success_matches_gcm_absorption_probability():
    """Always drift on the one-layer two-sink basin: the chance of ending in persistent group 0
    from a multiple-domicile cell is the GCM's absorption probability (thesis Thm 5.4.3)."""
    model = DrifterEnv(flow="two_sink").cell_model()
    gcm = layer_gcm(model, 0)
    group = np.asarray(gcm.groups[0])
    env = DrifterEnv(flow="two_sink",
                     goal={"cells": [tuple(c) for c in model.cells[group].tolist()]})
    start = int(model.state_of(0, 16, 19))
    row = int(np.flatnonzero(gcm.transient == start)[0])
    absorbed = gcm.absorption[row, 0]
    assert 0.3 < absorbed < 0.7  # a start whose fate is open
    horizon = 25
    policy = np.zeros(model.n_states, dtype=int)
    within = _reach_within(model, policy, group, start, horizon)
    assert abs(within - absorbed) < 1e-4  # the horizon cuts off almost nothing
    episodes = 2000
    rate = _monte_carlo(env, policy, (0, 16, 19), episodes, horizon)
    sigma = np.sqrt(absorbed * (1 - absorbed) / episodes)
    assert abs(rate - within) < 4 * sigma


def _greedy_reach_policy(model, goal: np.ndarray, sweeps: int) -> np.ndarray:
    """A fixed policy: greedy in the probability of reaching ``goal`` within ``sweeps`` steps
    (value iteration on the model's action matrices; illegal moves are never chosen)."""
    drift, up, down = model.action_matrices()
    value = np.zeros(model.n_states)
    for _ in range(sweeps):
        q = np.stack([drift @ value, np.where(model.legal[:, UP], up @ value, -1.0),
                      np.where(model.legal[:, DOWN], down @ value, -1.0)])
        value = np.maximum(q.max(axis=0), 0.0)
        value[goal] = 1.0
    return q.argmax(axis=0)


def test_cell_backend_success_of_a_layer_switching_policy_matches_the_model():
    env = DrifterEnv(**THREE, goal={"cell": (0, 11, 9), "halo": 1})
    model = env.cell_model()
    goal = env.task.region.states
    policy = _greedy_reach_policy(model, goal, 30)
    assert set(np.unique(policy)) == {DRIFT, UP, DOWN}
    start = int(model.state_of(1, 14, 17))
    assert policy[start] == DOWN
    horizon = 12
    p = _reach_within(model, policy, goal, start, horizon)
    assert 0.3 < p < 0.8
    episodes = 2000
    rate = _monte_carlo(env, policy, (1, 14, 17), episodes, horizon)
    assert abs(rate - p) < 4 * np.sqrt(p * (1 - p) / episodes)


# -- the continuous backend is `Drifters` ----------------------------------------------------
@pytest.mark.parametrize("diffusivity", [0.0, 30.0])
def test_continuous_backend_follows_the_rk4_drifters_exactly(diffusivity):
    field = get_flow("two_sink", n_layers=3)
    env = DrifterEnv(flow=field, backend="continuous", step_seconds=3000.0, substeps=3,
                     diffusivity=diffusivity, illegal_action="error")
    start = (7321.5, 12044.0)
    obs, info = env.reset(seed=5, options={"start": {"position": start, "layer": 0}})
    reference = Drifters(field, [start[0]], [start[1]], 0, diffusivity=diffusivity,
                         rng=np.random.default_rng(5))
    assert np.array_equal(info["position"], start)
    for action in [DRIFT, DOWN, DRIFT, DOWN, DRIFT, UP, DRIFT, DRIFT, UP, DRIFT]:
        _, _, _, _, info = env.step(action)
        reference.apply_actions([action])
        for _ in range(3):
            reference.step(1000.0)
        assert info["position"][0] == reference.x[0] and info["position"][1] == reference.y[0]
        assert info["layer"] == reference.layer[0] and info["time"] == reference.t


def test_continuous_default_step_is_the_median_crossing_time():
    field = get_flow("uniform", u=0.25, v=0.0)
    env = DrifterEnv(flow=field, backend="continuous")
    assert env.options.step_seconds == pytest.approx(1000.0 / 0.25)


# -- actions ---------------------------------------------------------------------------------
def test_illegal_move_drifts_and_is_flagged():
    env = DrifterEnv(**THREE)
    _, info = env.reset(seed=0, options={"start": (0, 10, 10)})
    assert info["action_mask"].tolist() == [1, 0, 1]
    assert env.action_masks().tolist() == [True, False, True]
    _, _, _, _, info = env.step(UP)  # no layer above the surface
    assert info["illegal_action"] and info["layer"] == 0
    _, _, _, _, info = env.step(DOWN)
    assert not info["illegal_action"] and info["layer"] == 1
    assert info["action_mask"].tolist() == [1, 1, 1]


def test_illegal_move_raises_when_asked():
    env = DrifterEnv(**THREE, illegal_action="error")
    env.reset(seed=0, options={"start": (2, 10, 10)})
    with pytest.raises(ActionError, match="down is illegal"):
        env.step(DOWN)


def test_land_below_makes_down_illegal():
    env = DrifterEnv()  # scb_like: the shelf makes coastal surface cells land further down
    model = env.cell_model()
    shelf = np.flatnonzero((model.cells[:, 0] == 0) & ~model.legal[:, DOWN])
    assert len(shelf)
    _, info = env.reset(seed=0, options={"start": tuple(model.cells[shelf[0]].tolist())})
    assert info["action_mask"].tolist() == [1, 0, 0]


@pytest.mark.parametrize("action", [3, -1, 1.0, True, "up", np.array([1])])
def test_actions_outside_the_space_raise(action):
    env = DrifterEnv(**THREE)
    env.reset(seed=0)
    with pytest.raises(ActionError, match="action"):
        env.step(action)


def test_step_before_reset_raises():
    with pytest.raises(gym.error.ResetNeeded):
        DrifterEnv(**THREE).step(DRIFT)


# -- sensing ---------------------------------------------------------------------------------
def test_fix_holds_the_last_surface_position_while_deep():
    env = DrifterEnv(**THREE, observe_fix=True, observe_pose=True, task="cover")
    obs, info = env.reset(seed=0, options={"start": (0, 10, 3)})
    layer, clock, fx, fy, fresh, px, py = obs
    assert (layer, clock, fresh) == (0.0, 0.0, 1.0) and (fx, fy) == (px, py)
    obs, *_ = env.step(DOWN)
    fix = obs[2:4].copy()
    assert obs[0] == 0.5 and obs[4] == 0.0 and np.array_equal(fix, obs[5:7])  # no move on DOWN
    for _ in range(5):
        obs, *_ = env.step(DRIFT)
        assert np.array_equal(obs[2:4], fix) and obs[4] == 0.0
    obs, _, _, _, info = env.step(UP)
    assert obs[4] == 1.0 and np.array_equal(obs[2:4], obs[5:7])
    assert obs[1] == pytest.approx(7 / 200)


def test_clock_reads_one_from_clock_steps_on():
    env = DrifterEnv(**THREE, task="cover", clock_steps=3)
    env.reset(seed=0)
    clocks = [env.step(DRIFT)[0][1] for _ in range(5)]
    assert clocks == pytest.approx([1 / 3, 2 / 3, 1, 1, 1])


def test_goal_features_follow_the_episode_goal():
    env = DrifterEnv(**THREE)
    obs, _ = env.reset(seed=0, options={"goal": (2, 0, 0)})
    x, y, layer = obs[-3:]
    assert layer == 1.0 and x == pytest.approx(0.5 / 29) and y == pytest.approx(0.5 / 21)


# -- tasks -----------------------------------------------------------------------------------
@pytest.mark.parametrize(("reward", "per_step", "at_goal"), [("success", 0.0, 1.0),
                                                            ("thesis", -1.0, 100.0)])
def test_reach_rewards_and_absorbing_goal(reward, per_step, at_goal):
    env = DrifterEnv(**THREE, reward=reward, goal=(1, 10, 10))
    env.reset(seed=0, options={"start": (0, 10, 10)})
    _, r, terminated, _, info = env.step(DOWN)  # deterministic: straight into the goal
    assert (r, terminated, info["is_success"], info["distance_to_goal"]) == (at_goal, True,
                                                                              True, 0.0)
    env.reset(seed=0, options={"start": (0, 10, 10)})
    _, r, terminated, _, info = env.step(UP)  # illegal: drifts instead
    assert (r, terminated) == (per_step, False) and info["distance_to_goal"] > 0


def test_start_in_the_goal_is_refused():
    env = DrifterEnv(**THREE, goal={"cell": (0, 10, 10), "halo": 1})
    with pytest.raises(ConfigError, match="options.start.*goal"):
        env.reset(seed=0, options={"start": (0, 11, 11)})
    for _ in range(20):  # random starts avoid the goal
        _, info = env.reset()
        assert info["state"] not in env.task.region.states


def test_stay_rewards_steps_in_the_region():
    env = DrifterEnv(**THREE, task="stay", region={"cell": (0, 6, 18), "halo": 1})
    _, info = env.reset(seed=0, options={"start": (0, 6, 18)})
    assert info["in_region"]
    rewards = []
    for _ in range(20):
        _, r, terminated, _, info = env.step(DRIFT)  # a persistent group: it stays near
        rewards.append(r)
        assert not terminated and r == float(info["in_region"])
    assert info["steps_in_region"] == sum(rewards) > 0


def test_cover_counts_new_region_cells():
    env = DrifterEnv(**THREE, task="cover")
    _, info = env.reset(seed=2)
    assert info["coverage"] == pytest.approx(1 / 522)
    seen = {info["cell"]}
    for _ in range(40):
        _, r, _, _, info = env.step(DRIFT)
        new = info["cell"] not in seen
        seen.add(info["cell"])
        assert r == info["new_cells"] == int(new)
    assert info["coverage"] == pytest.approx(len(seen) / 522)


# -- flows from files and objects ------------------------------------------------------------
def test_flow_from_a_netcdf_file_equals_the_zoo_field(tmp_path):
    path = save_flow(get_flow("two_sink", n_layers=3), tmp_path / "basin.nc")
    a = _rollout(DrifterEnv(flow=str(path)), 1, 60)
    b = _rollout(DrifterEnv(**THREE), 1, 60)
    assert data_equivalence(a, b, exact=True)


def test_time_dependent_flow_continuous_clock_and_hold():
    env = DrifterEnv(backend="continuous", step_seconds=7200.0, flow_kwargs={"hours": 6})
    env.reset(seed=0)
    times = [env.step(DRIFT)[4]["time"] for _ in range(5)]  # runs past the 6 h of the field
    assert times == [7200.0 * k for k in range(1, 6)]


# -- bad arguments ---------------------------------------------------------------------------
@pytest.mark.parametrize(("kwargs", "field"), [
    (dict(flow="no_such_flow"), "flow"),
    (dict(flow=3), "flow"),
    (dict(flow="missing.nc"), "flow"),
    (dict(flow="two_sink", flow_kwargs={"swril": 0.1}), "flow_kwargs"),
    (dict(flow="two_sink", flow_kwargs={"n_layers": 0}), "flow_kwargs"),
    (dict(flow=get_flow("two_sink"), flow_kwargs={"n_layers": 2}), "flow_kwargs"),
    (dict(backend="grid"), "backend"),
    (dict(rho=0.0), "rho"),
    (dict(rho=1.5), "rho"),
    (dict(cell_map="rk4"), "cell_map"),
    (dict(step_seconds=60.0), "step_seconds"),
    (dict(backend="continuous", step_seconds=-1.0), "step_seconds"),
    (dict(backend="continuous", substeps=0), "substeps"),
    (dict(backend="continuous", diffusivity=-1.0), "diffusivity"),
    (dict(backend="continuous", land_rule="bounce"), "land_rule"),
    (dict(flow="two_sink", start_time=10.0), "start_time"),
    (dict(start_time=1e9), "start_time"),
    (dict(illegal_action="ignore"), "illegal_action"),
    (dict(observe_fix=1), "observe_fix"),
    (dict(clock_steps=0), "clock_steps"),
    (dict(task="patrol"), "task"),
    (dict(reward="dense"), "reward"),
    (dict(task="cover", goal=(0, 1, 1)), "goal"),
    (dict(region={"layer": 0}), "region"),
    (dict(task="stay"), "region"),
    (dict(goal=None), "goal"),
    (dict(goal=(0, 20, 28)), "goal"),  # land in the north-east
    (dict(goal=(0, 5)), "goal"),
    (dict(goal=(3, 5, 5)), "goal"),
    (dict(goal={"cell": (0, 5, 5), "halo": -1}), "goal.halo"),
    (dict(goal={"cells": []}), "goal"),
    (dict(goal={"position": (0.0, 0.0)}), "goal.position"),
    (dict(goal={"position": (-118.0, 33.5), "radius": -5.0}), "goal.radius"),
    (dict(goal={"position": (-118.0, 33.5), "depth": 3}), "goal"),
    (dict(start=(0, 5, 5)), "start"),
    (dict(render_mode="video"), "render_mode"),
    (dict(field_style="contours"), "field_style"),
])
def test_bad_arguments_raise_config_error_naming_the_field(kwargs, field):
    with pytest.raises(ConfigError, match=f"^{field}"):
        env = DrifterEnv(**kwargs)
        env.reset(seed=0)


def test_unreadable_flow_file_is_a_config_error(tmp_path):
    path = tmp_path / "field.nc"
    path.write_bytes(b"import os; os.system('echo never run')\n")
    with pytest.raises(ConfigError, match="^flow: .*not a readable NetCDF"):
        DrifterEnv(flow=path)


def test_a_flow_file_is_capped_by_flow_kwargs(tmp_path):
    path = save_flow(get_flow("two_sink", n_layers=3), tmp_path / "basin.nc")
    with pytest.raises(ConfigError, match=r"^flow: .*basin.nc: u \('u'\): declares [\d,]+ values "
                                          r".*at most 100 are read"):
        DrifterEnv(flow=path, flow_kwargs={"max_values": 100})
    with pytest.raises(ConfigError, match="^flow_kwargs: a NetCDF file takes only 'mapping' and "
                                          "'max_values', got \\['hours'\\]"):
        DrifterEnv(flow=path, flow_kwargs={"hours": 6})
    assert DrifterEnv(flow=path, flow_kwargs={"max_values": 10**6}).options.flow.n_layers == 3


def test_unknown_arguments_and_reset_options():
    with pytest.raises(TypeError, match="deploy"):
        DrifterEnv(deploy=[(0, 1, 1)])
    env = DrifterEnv(**THREE)
    with pytest.raises(ConfigError, match="unknown keys"):
        env.reset(seed=0, options={"goal_cell": 3})
    with pytest.raises(ConfigError, match="^options.goal"):
        env.reset(seed=0, options={"goal": (0, 20, 28)})
