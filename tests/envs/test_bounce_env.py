"""`BounceEnv`: the Gymnasium and SB3 checkers, the de-facto third-party suite (determinism,
pickling, render modes), memory over many resets, argument errors and the tasks' behaviour."""

import contextlib
import gc
import math
import pickle
import sys
import tracemalloc
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence

import bounce_gym  # noqa: F401  (registers the ids)
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.registration import GYM_ENVS
from bounce_gym.errors import ActionError, ConfigError

IDS = list(GYM_ENVS)
#: the goal-conditioned id: discrete actions only, a Dict observation
GOAL_ID = "bounce_gym/BounceNavigation-v1"
#: (id, action type) pairs every id takes
ID_ACTIONS = [(env_id, action) for env_id in IDS for action in ("discrete", "continuous")
              if not (env_id == GOAL_ID and action == "continuous")]
#: the ids with a flat observation that starts with what the robot senses
FLAT_IDS = [env_id for env_id in IDS if env_id != GOAL_ID]
#: the continuous models: exact (kinematic, pymunk ideal) and physical (pymunk dynamic)
BACKENDS = [pytest.param({"backend": "kinematic"}, id="kinematic"),
            pytest.param({"backend": "pymunk", "physics": "ideal"}, id="pymunk-ideal"),
            pytest.param({"backend": "pymunk"}, id="pymunk-dynamic")]
EXACT = BACKENDS[:2]
ACTION_TYPES = ["discrete", "continuous"]
STEP_MODES = ["bounce", "tick"]

SQUARE_LOOP_START = {"position": [1.5, 0.5], "heading": 0.0}
MAX_CLOCK_SQUARE = 16  # ceil(10 * sqrt(2)) + 1


@contextlib.contextmanager
def no_warnings():
    """Record every warning, whatever the filters say; the caller asserts the list is empty."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        messages = []
        yield messages
    # Gymnasium's own notice on making an id that has a newer version (v0 beside v1) is the
    # convention for a changed task, not a defect of the env
    messages.extend(f"{w.category.__name__}: {w.message}" for w in caught
                    if "is out of date" not in str(w.message))


def make(env_id, **kwargs):
    """``gym.make`` — for continuous actions the localization id runs on the kinematic backend
    without its combinatorial filter: both the cell backend and the filter need discrete angles
    (those combinations raise; see the tests below)."""
    if kwargs.get("action_type") == "continuous" and env_id == "bounce_gym/BounceLocalization-v0":
        kwargs["task_kwargs"] = {"filter_factory": None}
        kwargs.setdefault("backend", "kinematic")
    return gym.make(env_id, **kwargs)


def square_env(**kwargs):
    kwargs.setdefault("world", "square")
    kwargs.setdefault("angles", [90.0])
    return BounceEnv(**kwargs)


# -- Gymnasium's and SB3's checkers -------------------------------------------------------------

@pytest.mark.parametrize("step_mode", STEP_MODES)
@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_check_env_on_the_cell_backend(env_id, step_mode):
    env = gym.make(env_id, backend="cell", step_mode=step_mode)
    with no_warnings() as rec:
        check_env(env.unwrapped, skip_render_check=True)
    assert rec == []


def test_localization_filter_needs_discrete_actions():
    with pytest.raises(ConfigError, match="needs discrete actions"):
        gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic", action_type="continuous")


@pytest.mark.parametrize("step_mode", STEP_MODES)
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("env_id", "action_type"), ID_ACTIONS)
def test_gymnasium_check_env(env_id, backend, action_type, step_mode):
    env = make(env_id, **backend, action_type=action_type, step_mode=step_mode)
    with no_warnings() as rec:
        check_env(env.unwrapped, skip_render_check=True)
    assert rec == []
    env.close()


@pytest.mark.parametrize("step_mode", STEP_MODES)
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("env_id", "action_type"), ID_ACTIONS)
def test_passive_env_checker(env_id, backend, action_type, step_mode):
    with no_warnings() as rec:
        env = make(env_id, **backend, action_type=action_type, step_mode=step_mode)
        env.reset(seed=1)
        env.action_space.seed(1)
        for _ in range(10):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if terminated or truncated:
                env.reset()
        env.close()
    assert rec == []


@pytest.mark.parametrize("step_mode", STEP_MODES)
@pytest.mark.parametrize(("env_id", "action_type"), ID_ACTIONS)
def test_sb3_check_env(env_id, action_type, step_mode):
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = make(env_id, action_type=action_type, step_mode=step_mode).unwrapped
    with no_warnings() as rec:
        sb3_check_env(env, warn=True)
    assert rec == []


# -- determinism and pickling -------------------------------------------------------------------

def _assert_same_step(a, b, where):
    for name, x, y in zip(("obs", "reward", "terminated", "truncated", "info"), a, b, strict=True):
        assert data_equivalence(x, y, exact=True), f"{where}: {name} differs: {x!r} vs {y!r}"


@pytest.mark.parametrize("step_mode", STEP_MODES)
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("env_id", IDS)
def test_determinism_rollout(env_id, backend, step_mode):
    """Gymnasium's test_env_determinism_rollout: 50 exactly equal steps of two instances."""
    env_1 = gym.make(env_id, **backend, step_mode=step_mode)
    env_2 = gym.make(env_id, **backend, step_mode=step_mode)
    obs_1, info_1 = env_1.reset(seed=0)
    obs_2, info_2 = env_2.reset(seed=0)
    assert data_equivalence(obs_1, obs_2, exact=True)
    assert data_equivalence(info_1, info_2, exact=True)
    env_1.action_space.seed(0)
    for t in range(50):
        action = env_1.action_space.sample()
        step_1 = env_1.step(action)
        step_2 = env_2.step(action)
        assert env_1.observation_space.contains(step_1[0])
        _assert_same_step(step_1, step_2, f"step {t}")
        if step_1[2] or step_1[3]:
            obs_1, _ = env_1.reset(seed=t)
            obs_2, _ = env_2.reset(seed=t)
            assert data_equivalence(obs_1, obs_2, exact=True)
    env_1.close()
    env_2.close()


@pytest.mark.parametrize("wrapped", [False, True], ids=["unwrapped", "gym_make"])
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("env_id", IDS)
def test_pickle_mid_episode(env_id, backend, wrapped):
    env = gym.make(env_id, **backend)
    if not wrapped:
        env = env.unwrapped
    env.reset(seed=3)
    env.action_space.seed(3)
    for _ in range(7):
        env.step(env.action_space.sample())
    clone = pickle.loads(pickle.dumps(env))
    assert type(clone) is type(env)
    for t in range(50):
        action = env.action_space.sample()
        step_1, step_2 = env.step(action), clone.step(action)
        _assert_same_step(step_1, step_2, f"step {t} after unpickling")
        if step_1[2] or step_1[3]:
            assert data_equivalence(env.reset(seed=t), clone.reset(seed=t), exact=True)
    if wrapped:  # the TimeLimit counter travels with the env
        assert clone._elapsed_steps == env._elapsed_steps


# -- rendering (skipped until the renderer lands) -----------------------------------------------

@pytest.mark.parametrize("env_id", IDS)
def test_check_env_with_render_modes(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    with no_warnings() as rec:
        check_env(env.unwrapped)
    assert rec == []
    env.close()


@pytest.mark.parametrize("step_mode", STEP_MODES)
@pytest.mark.parametrize("env_id", IDS)
def test_render_rgb_array_after_reset_and_step(env_id, step_mode):
    env = gym.make(env_id, render_mode="rgb_array", step_mode=step_mode)
    env.reset(seed=0)
    frames = [env.render()]
    env.action_space.seed(0)
    env.step(env.action_space.sample())
    frames.append(env.render())
    for frame in frames:
        assert isinstance(frame, np.ndarray) and frame.dtype == np.uint8
        assert frame.ndim == 3 and frame.shape[2] == 3 and frame.shape[0] > 0 and frame.shape[1] > 0
    assert frames[0].shape == frames[1].shape
    clone = pickle.loads(pickle.dumps(env))  # the pygame renderer is dropped and rebuilt
    np.testing.assert_array_equal(clone.render(), frames[1])
    env.close()
    env.close()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("env_id", IDS)
def test_rendering_does_not_change_observations(env_id, backend):
    plain = gym.make(env_id, **backend)
    drawn = gym.make(env_id, **backend, render_mode="rgb_array")
    assert data_equivalence(plain.reset(seed=5), drawn.reset(seed=5), exact=True)
    drawn.render()
    plain.action_space.seed(5)
    for t in range(20):
        action = plain.action_space.sample()
        step_1, step_2 = plain.step(action), drawn.step(action)
        drawn.render()
        _assert_same_step(step_1, step_2, f"step {t}")
        if step_1[2] or step_1[3]:
            assert data_equivalence(plain.reset(seed=t), drawn.reset(seed=t), exact=True)
    drawn.close()


# -- memory -------------------------------------------------------------------------------------

@pytest.mark.timeout(60)
@pytest.mark.parametrize("backend", BACKENDS)
def test_memory_flat_over_10000_resets(backend):
    """10,000 resets (round-robin over every registered id) leave no Python objects behind.

    sys.getallocatedblocks counts live pymalloc blocks at no tracing cost, so the full 10,000
    resets run untraced; a window of 1,000 resets is then measured with tracemalloc (< 100 kB,
    i.e. < 1 MB per 10,000 resets). A pymunk reset places the bodies of its one Space again.
    """
    envs = [gym.make(env_id, **backend).unwrapped for env_id in IDS]
    for seed, env in enumerate(envs):
        env.reset(seed=seed)
        env.step(env.action_space.sample())

    def resets(n):
        for k in range(n):
            envs[k % len(envs)].reset()

    resets(1_000)
    gc.collect()
    blocks = sys.getallocatedblocks()
    resets(10_000)
    gc.collect()
    assert sys.getallocatedblocks() - blocks < 1_000  # one leaked object per reset = 10,000

    tracemalloc.start()
    try:
        resets(200)  # every live object is now one tracemalloc saw being allocated
        gc.collect()
        before = tracemalloc.take_snapshot()
        resets(1_000)
        gc.collect()
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    growth = sum(stat.size_diff for stat in after.compare_to(before, "filename"))
    assert growth < 100_000, f"{growth} bytes retained over 1,000 resets"


@pytest.mark.parametrize("backend", BACKENDS)
def test_reset_leaves_no_cyclic_garbage(backend):
    """Memory of an old episode is freed by reference counting, not only by the cyclic GC."""
    env = gym.make("bounce_gym/Bounce-v0", **backend).unwrapped
    env.reset(seed=0)
    env.step(0)
    gc.collect()
    gc.disable()
    try:
        for _ in range(20):
            env.reset()
        garbage = gc.collect()
    finally:
        gc.enable()
    assert garbage == 0


# -- argument errors ----------------------------------------------------------------------------

CONFIG_ERRORS = {
    "unknown world": ({"world": "atlantis"}, "world"),
    "missing map file": ({"world": "/no/such/map.yaml"}, "world"),
    "angle 0, relative rule": ({"angles": [0.0]}, "angles"),
    "angle 360, relative rule": ({"angles": [360.0]}, "angles"),
    "empty angle set": ({"angles": []}, "angles"),
    "duplicate angles": ({"angles": [90.0, 90.0]}, "angles"),
    "angle 180, fixed rule": ({"bounce_rule": "fixed", "angles": [180.0]}, "angles"),
    "angles not a list": ({"angles": "90"}, "angles"),
    "negative radius": ({"robot_radius": -0.5}, "robot_radius"),
    "NaN radius": ({"robot_radius": float("nan")}, "robot_radius"),
    "zero step length": ({"step_length": 0}, "step_length"),
    "unknown backend": ({"backend": "box2d"}, "backend"),
    "cell backend, fixed rule": ({"backend": "cell", "bounce_rule": "fixed"}, "bounce_rule"),
    "cell backend, angle not a bin": ({"backend": "cell", "angles": [30.0]}, "angles"),
    "cell backend, continuous": ({"backend": "cell", "action_type": "continuous"}, "action_type"),
    "cell backend, bad bins": ({"backend": "cell", "cell_bins": 7}, "cell_bins"),
    "cell backend, eps not a bin": ({"backend": "cell",
                                     "noise": {"type": "reliable", "r": 0.8, "eps_deg": 10}},
                                    "eps"),
    "cell backend, corner rule": ({"backend": "cell", "corner_rule": "squeeze"}, "corner_rule"),
    "unknown task": ({"task": "racing"}, "task"),
    "multi-robot task": ({"task": "monitoring"}, "task"),
    "unknown bounce rule": ({"bounce_rule": "random"}, "bounce_rule"),
    "bad step mode": ({"step_mode": "ticks"}, "step_mode"),
    "bad action type": ({"action_type": "multi"}, "action_type"),
    "negative history": ({"history": -1}, "history"),
    "float history": ({"history": 1.5}, "history"),
    "privileged not bool": ({"privileged": "yes"}, "privileged"),
    "unknown task_kwargs key": ({"task": "navigation", "task_kwargs": {"bogus": 1}},
                                "task_kwargs.*bogus"),
    "task_kwargs not a dict": ({"task": "coverage", "task_kwargs": [1]}, "task_kwargs"),
    "bad goal radius": ({"task": "navigation", "task_kwargs": {"goal_radius": -1}},
                        "goal_radius"),
    "w2 < w1": ({"task": "navigation", "task_kwargs": {"w1": 5, "w2": 1}}, "w2"),
    "bogus render mode": ({"render_mode": "bogus"}, "render_mode"),
    "unknown noise model": ({"noise": {"type": "gauss"}}, "noise"),
    "angle range too wide": ({"action_type": "continuous", "angle_range": (10, 400)},
                             "angle_range"),
}


@pytest.mark.parametrize("kwargs, field", CONFIG_ERRORS.values(), ids=CONFIG_ERRORS.keys())
def test_bad_arguments_raise_config_error(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        BounceEnv(**kwargs)
    with pytest.raises(ValueError):  # the package errors are ValueErrors
        BounceEnv(**kwargs)


RESET_ERRORS = {
    "unknown option key": ({}, {"bogus": 1}, "bogus"),
    "navigation key on free task": ({}, {"goal": {"position": [1, 1], "heading": 0}}, "goal"),
    "options not a dict": ({}, "start", "options"),
    "start outside": ({}, {"start": {"position": [100.0, 100.0], "heading": 0.0}}, "start"),
    "start without heading": ({}, {"start": {"position": [1.0, 1.0]}}, "start"),
    "goal outside": ({"world": "square", "task": "navigation"},
                     {"goal": {"position": [50.0, 5.0], "heading": 0.0}}, "goal"),
}


@pytest.mark.parametrize("kwargs, options, field", RESET_ERRORS.values(), ids=RESET_ERRORS.keys())
def test_bad_reset_options_raise_config_error(kwargs, options, field):
    env = BounceEnv(**kwargs)
    with pytest.raises(ConfigError, match=field):
        env.reset(seed=0, options=options)


ACTION_ERRORS = {
    "float for discrete": ("discrete", 1.0, "integer index"),
    "numpy float for discrete": ("discrete", np.float32(1.0), "integer index"),
    "index out of range": ("discrete", 3, "out of range"),
    "negative index": ("discrete", -1, "out of range"),
    "bool for discrete": ("discrete", True, "bool"),
    "two indices": ("discrete", np.array([0, 1]), "shape"),
    "string for discrete": ("discrete", "1", "integer index"),
    "shape (2,) for continuous": ("continuous", np.zeros(2, dtype=np.float32), "shape"),
    "shape (1, 1) for continuous": ("continuous", np.zeros((1, 1), dtype=np.float32), "shape"),
    "NaN for continuous": ("continuous", np.array([np.nan], dtype=np.float32), "finite"),
    "1.5 for continuous": ("continuous", np.array([1.5], dtype=np.float32), "outside"),
    "-1.0001 for continuous": ("continuous", -1.0001, "outside"),
    "string for continuous": ("continuous", "x", "number"),
}


@pytest.mark.parametrize("action_type, action, detail", ACTION_ERRORS.values(),
                         ids=ACTION_ERRORS.keys())
def test_bad_actions_raise_action_error(action_type, action, detail):
    env = BounceEnv(action_type=action_type)
    _, info = env.reset(seed=0)
    with pytest.raises(ActionError, match=rf"^action: .*{detail}"):
        env.step(action)
    # the rejected action did nothing: the env steps on from where it was
    _, _, _, _, after = env.step(env.action_space.sample())
    assert after["bumps"] == info["bumps"] + 1


def test_step_before_reset_raises():
    with pytest.raises(gym.error.ResetNeeded):
        BounceEnv().step(0)


# -- behaviour: sensing -------------------------------------------------------------------------

@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("env_id", FLAT_IDS)
def test_bounce_mode_every_step_ends_in_contact(env_id, backend):
    """Every bounce-mode step ends against a wall — so a lone robot's observation leaves out
    ``contact`` (it would always read 1) and starts with the clock."""
    env = gym.make(env_id, **backend)
    base = env.unwrapped
    assert not base.core.observes_contact
    obs, info = env.reset(seed=11)
    assert base.robot_state.blocked[0]
    assert obs[0] == np.float32(info["clock"] / base.options.max_clock)
    rows, cols = env.unwrapped.world.occupancy(1.0).shape
    env.action_space.seed(11)
    for _ in range(60):
        bumps = info["bumps"]
        obs, _, terminated, truncated, info = env.step(env.action_space.sample())
        assert base.robot_state.blocked[0]
        assert obs[0] == np.float32(info["clock"] / base.options.max_clock)
        assert 0 <= info["cell"][0] < rows and 0 <= info["cell"][1] < cols
        assert info["bumps"] == bumps + 1  # exactly one bump per bounce-mode step
        assert info["step_ticks"] == 1 + info["clock"]
        if terminated or truncated:
            obs, info = env.reset()
            assert base.robot_state.blocked[0]


@pytest.mark.parametrize("backend", EXACT)
def test_square_wall_loop_clock_bounce_mode(backend):
    """(1.5, 0.5) heading East in the 10 x 10 square, φ = 90° (relative): the CCW wall loop.

    Reset drives 8.5 units = 9 ticks to (10, 0.5). The first bounce turns North (1 bump tick)
    and drives 9.5 units = 10 ticks to (10, 10); every later bounce is 1 + 10 ticks along a
    10-unit wall.
    """
    env = square_env(**backend)
    obs, info = env.reset(seed=0, options={"start": SQUARE_LOOP_START})
    np.testing.assert_allclose(info["position"], [10.0, 0.5], atol=1e-9)
    assert (info["clock"], info["ticks"], info["bumps"]) == (9, 9, 0)
    assert info["cell"] == (0, 9)  # (row, col) of the 10 x 10 grid, even on the right wall
    assert obs.shape == (1,) and obs[0] == np.float32(9 / MAX_CLOCK_SQUARE)  # clock only
    corners = [(10, 10), (0, 10), (0, 0), (10, 0), (10, 10), (0, 10)]
    cells = [(9, 9), (9, 0), (0, 0), (0, 9), (9, 9), (9, 0)]
    ticks = 9
    for k, (corner, cell) in enumerate(zip(corners, cells, strict=True)):
        obs, reward, terminated, truncated, info = env.step(0)
        ticks += 11
        np.testing.assert_allclose(info["position"], corner, atol=1e-9)
        assert info["cell"] == cell
        assert info["heading"] == pytest.approx(math.radians(90 * (k + 1) % 360), abs=1e-9)
        assert (info["clock"], info["step_ticks"], info["ticks"], info["bumps"]) == (
            10, 11, ticks, k + 1)
        assert obs[0] == np.float32(10 / MAX_CLOCK_SQUARE)
        assert reward == 0.0 and not terminated and not truncated


@pytest.mark.parametrize("backend", EXACT)
def test_square_wall_loop_clock_tick_mode(backend):
    env = square_env(**backend, step_mode="tick")
    obs, info = env.reset(seed=0, options={"start": SQUARE_LOOP_START})
    assert obs[0] == 0.0 and obs[1] == 0.0 and info["clock"] == 0
    clocks, contacts = [], []
    for _ in range(9 + 11 + 11):
        obs, _, _, _, info = env.step(0)
        clocks.append(info["clock"])
        contacts.append(int(obs[0]))
        assert obs[1] == np.float32(info["clock"] / MAX_CLOCK_SQUARE)
    assert clocks == list(range(1, 10)) + [0, *range(1, 11)] + [0, *range(1, 11)]
    assert [t for t, c in enumerate(contacts, start=1) if c] == [9, 20, 31]
    assert info["step_ticks"] == 1 and info["ticks"] == 31 and info["bumps"] == 2
    np.testing.assert_allclose(info["position"], [0.0, 10.0], atol=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
def test_tick_and_bounce_mode_give_the_same_contacts(backend):
    rng = np.random.default_rng(2)
    actions = rng.integers(0, 3, size=30).tolist()
    bounce = BounceEnv(**backend)
    tick = BounceEnv(**backend, step_mode="tick")
    _, info = bounce.reset(seed=7)
    expected = [(info["ticks"], info["bumps"], info["position"])]
    for a in actions:
        _, _, _, _, info = bounce.step(a)
        expected.append((info["ticks"], info["bumps"], info["position"]))

    obs, info = tick.reset(seed=7)
    got, queue = [], list(actions)
    while len(got) < len(expected):
        if obs[0] == 1.0:
            got.append((info["ticks"], info["bumps"], info["position"]))
            if not queue:
                break
            obs, _, _, _, info = tick.step(queue.pop(0))
        else:
            obs, _, _, _, info = tick.step(2)  # ignored: not a bump tick
        assert info["ticks"] < 5_000
    assert len(got) == len(expected)
    for (t1, b1, p1), (t2, b2, p2) in zip(expected, got, strict=True):
        assert (t1, b1) == (t2, b2)
        np.testing.assert_allclose(p1, p2, atol=1e-9)


@pytest.mark.parametrize("step_mode", STEP_MODES)
def test_history_holds_last_pairs_newest_first(step_mode):
    k = 3
    env = square_env(angles=[90.0, 135.0, 180.0], history=k, step_mode=step_mode)
    obs, info = env.reset(seed=4)
    max_clock = env.options.max_clock
    sensed = 2 if step_mode == "tick" else 1  # contact (tick mode only) and clock
    assert obs.shape == (sensed + 2 * k,)
    np.testing.assert_array_equal(obs[sensed:], 0.0)
    expected = []
    degrees = [90.0, 135.0, 180.0]
    rng = np.random.default_rng(0)
    for _ in range(40):
        action = int(rng.integers(3))
        if env.robot_state.blocked[0]:  # this step starts with a bump: one new pair
            expected.insert(0, (info["clock"] / max_clock, degrees[action] / 360.0))
        obs, _, _, _, info = env.step(action)
        want = np.zeros(2 * k, dtype=np.float32)
        flat = np.array(expected[:k], dtype=np.float32).ravel()
        want[:len(flat)] = flat
        np.testing.assert_allclose(obs[sensed:], want, rtol=1e-6, atol=0)
    assert len(expected) > k


def test_privileged_appends_true_pose():
    env = BounceEnv(world="square", privileged=True)
    assert env.observation_space.shape == (5,)
    obs, info = env.reset(seed=2)
    for _ in range(10):
        x, y = info["position"]
        h = info["heading"]
        np.testing.assert_allclose(obs[1:], [x / 10, y / 10, math.cos(h), math.sin(h)],
                                   atol=1e-6)
        obs, _, _, _, info = env.step(env.action_space.sample())
    # layout: contact (tick mode only), clock, history, pose, task features
    nav = gym.make("bounce_gym/BounceNavigation-v0", privileged=True).unwrapped
    assert nav.observation_space.shape == (1 + 2 * 4 + 4 + 8,)
    nav = gym.make("bounce_gym/BounceNavigation-v0", privileged=True, step_mode="tick")
    assert nav.unwrapped.observation_space.shape == (2 + 2 * 4 + 4 + 8,)
    assert BounceEnv(world="square").observation_space.shape == (1,)
    assert BounceEnv(world="square", step_mode="tick").observation_space.shape == (2,)


# -- behaviour: tasks ---------------------------------------------------------------------------

def test_navigation_tick_mode_reaches_goal_and_charges_ticks():
    """(1.5, 5) East to the goal disc of radius 1 about (5, 5): entered at x = 4, in tick 3."""
    env = square_env(task="navigation", step_mode="tick", task_kwargs={"reward": "plan_cost"})
    env.reset(seed=0, options={"start": {"position": [1.5, 5.0], "heading": 0.0},
                               "goal": {"position": [5.0, 5.0], "heading": 0.0}})
    rewards = []
    for _ in range(3):
        _, reward, terminated, truncated, info = env.step(0)
        rewards.append(reward)
    assert rewards == [-1.0, -1.0, -1.0 + 100.0]
    assert terminated and not truncated and info["is_success"] is True
    assert info["plan_cost"] == 3.0
    np.testing.assert_allclose(info["goal_position"], [5.0, 5.0])


@pytest.mark.parametrize("backend", BACKENDS)
def test_navigation_bounce_mode_terminates_on_first_step(backend):
    """Reset drives to (10, 0.5); the first bounce turns North along x = 10 and enters the disc
    of radius 1 about (9.5, 5) after 4.5 - sqrt(0.75) = 3.63 units: 1 bump + 4 drive ticks."""
    env = square_env(task="navigation", **backend,
                     task_kwargs={"goal": {"position": [9.5, 5.0], "heading": math.pi / 2},
                                  "reward": "plan_cost", "w1": 1.0, "w2": 100.0,
                                  "goal_bonus": 50.0})
    _, info = env.reset(seed=0, options={"start": SQUARE_LOOP_START})
    assert info["is_success"] is False
    assert info["plan_cost"] == 9.0  # the reset's drive: 9 ticks, not charged by the reward
    _, reward, terminated, truncated, info = env.step(0)
    assert reward == -5.0 + 50.0
    assert info["plan_cost"] == 9.0 + 5.0
    assert terminated and not truncated and info["is_success"] is True
    assert info["angle_changed"] is False  # the first angle is free


def test_navigation_angle_change_costs_w2_minus_w1():
    env = square_env(angles=[90.0, 135.0], task="navigation",
                     task_kwargs={"goal": {"position": [5.0, 5.0], "heading": 0.3},
                                  "heading_tolerance_deg": 1.0, "reward": "plan_cost",
                                  "w1": 2.0, "w2": 30.0})
    _, info = env.reset(seed=0, options={"start": SQUARE_LOOP_START})
    cost = info["plan_cost"]
    for action, changed in zip([0, 0, 1, 1, 0, 1], [False, False, True, False, True, True],
                               strict=True):
        _, reward, terminated, _, info = env.step(action)
        assert info["angle_changed"] is changed
        assert reward == -2.0 * info["step_ticks"] - 28.0 * changed
        assert info["plan_cost"] - cost == -reward  # the papers' cost, as the reward charges it
        cost = info["plan_cost"]
        assert not terminated


def test_navigation_observes_start_and_goal():
    env = square_env(task="navigation")
    obs, _ = env.reset(seed=0, options={"start": {"position": [2.5, 5.0], "heading": 0.0},
                                        "goal": {"position": [7.5, 2.5], "heading": math.pi}})
    np.testing.assert_allclose(obs[-8:], [-0.5, 0.0, 1.0, 0.0, 0.5, -0.5, -1.0, 0.0], atol=1e-6)


def test_coverage_improves_over_random_rollout():
    env = gym.make("bounce_gym/BounceCoverage-v0").unwrapped
    _, info = env.reset(seed=0)
    infos, total = [info], 0.0
    env.action_space.seed(0)
    for _ in range(300):
        _, reward, terminated, truncated, info = env.step(env.action_space.sample())
        total += reward
        infos.append(info)
        assert not terminated and not truncated
    coverage = [i["coverage"] for i in infos]
    assert all(0.0 <= c <= 1.0 for c in coverage)
    assert coverage == sorted(coverage)  # visited cells stay visited
    early, late = infos[10], infos[-1]
    assert late["coverage"] > early["coverage"] and late["coverage"] > 0.5
    assert late["distance"] < early["distance"]
    assert late["tv_distance"] < early["tv_distance"]
    # rewards telescope: covered fraction gained plus L2 distance lost
    first = infos[0]
    expected = (late["coverage"] - first["coverage"]) + (first["distance"] - late["distance"])
    assert total == pytest.approx(expected, abs=1e-9)


def test_coverage_custom_target(tmp_path):
    target = np.zeros((10, 10))
    target[:5] = 1.0  # the bottom half of the square
    path = tmp_path / "target.npy"
    np.save(path, target)
    env = BounceEnv(world="square", task="coverage", task_kwargs={"target": str(path)})
    np.testing.assert_allclose(env.task.target, target / target.sum())
    _, info = env.reset(seed=0)
    assert info["distance"] == pytest.approx(np.hypot.reduce((target / 50).ravel()))


def _blocked_target():
    free = BounceEnv(world="two_rooms", task="coverage").task.free
    assert not free.all()
    return np.ones(free.shape)


COVERAGE_TARGET_ERRORS = {
    "wrong shape": ("square", lambda: np.ones((3, 3)), "shape"),
    "negative": ("square", lambda: -np.ones((10, 10)), ">= 0"),
    "NaN": ("square", lambda: np.full((10, 10), np.nan), "finite"),
    "zero sum": ("square", lambda: np.zeros((10, 10)), "positive sum"),
    "mass on blocked cells": ("two_rooms", _blocked_target, "blocked"),
    "missing file": ("square", lambda: "/no/such/target.npy", "cannot read"),
}


@pytest.mark.parametrize("world, make_target, detail", COVERAGE_TARGET_ERRORS.values(),
                         ids=COVERAGE_TARGET_ERRORS.keys())
def test_coverage_target_validation(world, make_target, detail):
    with pytest.raises(ConfigError, match=rf"coverage target: .*{detail}"):
        BounceEnv(world=world, task="coverage", task_kwargs={"target": make_target()})


@pytest.mark.parametrize("step_mode", STEP_MODES)
def test_localization_without_filter_reports_observations(step_mode):
    env = gym.make("bounce_gym/BounceLocalization-v0", step_mode=step_mode,
                   task_kwargs={"filter_factory": None}).unwrapped
    _, info = env.reset(seed=3)
    assert info["observation"] is None and info["observation_count"] == 0
    assert "candidates" not in info
    phi = math.radians(45.0)
    sensed = []
    for t in range(1, 31):
        _, reward, terminated, _, info = env.step(0)
        assert reward == 0.0 and not terminated
        assert info["observation_count"] == t
        bumps, clock, angle = info["observation"]
        sensed.append(bumps)
        assert clock == info["clock"]
        if bumps:
            assert angle == phi
        else:
            assert step_mode == "tick" and angle is None
    assert set(sensed) == ({1} if step_mode == "bounce" else {0, 1})
    _, info = env.reset(seed=4)
    assert info["observation"] is None and info["observation_count"] == 0


def test_localization_info_does_not_grow_with_the_episode():
    """info holds the last step's observation, not the history: its size stays put."""
    env = BounceEnv(world="lab_localization_a", angles=(45.0,), backend="cell",
                    task="localization")
    env.reset(seed=0)
    sizes = []
    for t in range(1, 3001):
        _, _, _, _, info = env.step(0)
        if t in (10, 3000):
            sizes.append(len(pickle.dumps(info)))
    assert sizes[1] <= sizes[0] + 8  # a few bytes for larger counters, not one entry per step


class HalvingFilter:
    """Test double of the documented filter protocol: every bump halves the candidate set."""

    def __init__(self, options, start=16):
        self.options = options
        self.start = start
        self.updates = []

    def reset(self):
        self.size = self.start
        self.updates = []

    def update(self, symbol, angle):
        self.updates.append((symbol, angle))
        if symbol == 1:
            self.size = max(self.size // 2, 1)

    @property
    def localized(self):
        return self.size == 1


@pytest.mark.parametrize("step_mode", STEP_MODES)
def test_localization_with_filter_rewards_log2_drop_minus_ticks(step_mode):
    """Reward = drop in log2(candidates) − tick_cost per tick up to the tick the filter first
    reports ``localized`` (``info["ticks_to_localize"]``, counted from the episode start)."""
    filters = []

    def factory(options):
        filters.append(HalvingFilter(options, start=12))
        return filters[-1]

    env = BounceEnv(world="lab_localization_a", angles=[45.0], task="localization",
                    task_kwargs={"filter_factory": factory, "tick_cost": 0.25},
                    step_mode=step_mode)
    assert len(filters) == 1 and filters[0].options.world.name == "lab_localization_a"
    _, info = env.reset(seed=1)
    assert (info["candidates"], info["localized"]) == (12, False)
    assert "ticks_to_localize" not in info
    start_ticks = info["ticks"]
    sizes, rewards, bumps, charged = [12], [], 0, []
    terminated = False
    while not terminated:
        before = info["ticks"]
        _, reward, terminated, truncated, info = env.step(0)
        rewards.append(reward)
        sizes.append(info["candidates"])
        bumps += info["observation"][0]
        charged.append(info.get("ticks_to_localize", info["ticks"]) - before)
        assert len(rewards) < 500 and not truncated
    assert sizes[-1] == 1 and info["localized"] is True
    assert list(dict.fromkeys(sizes)) == [12, 6, 3, 1]
    # localized on the bump tick that halved 3 to 1: the first tick of the last step
    assert info["ticks_to_localize"] == info["ticks"] - info["step_ticks"] + 1
    assert charged[-1] == 1
    for reward, before, after, ticks in zip(rewards, sizes[:-1], sizes[1:], charged,
                                            strict=True):
        assert reward == pytest.approx(math.log2(before) - math.log2(after) - 0.25 * ticks)
    assert sum(rewards) == pytest.approx(
        math.log2(12) - 0.25 * (info["ticks_to_localize"] - start_ticks))
    updates = filters[0].updates
    # one symbol per tick since reset (incl. the drive to the first contact in bounce mode);
    # bumps carry the angle used, forward ticks none
    assert len(updates) == info["ticks"]
    assert sum(symbol for symbol, _ in updates) == bumps
    assert all(a == pytest.approx(math.radians(45.0)) for symbol, a in updates if symbol == 1)
    assert all(a is None for symbol, a in updates if symbol == 0)
    if step_mode == "bounce":
        assert len(rewards) == 3  # 12 -> 6 -> 3 -> 1
    # a new episode resets the filter
    _, info = env.reset()
    # …and feeds it only the drive to the first contact (bounce mode) or nothing (tick mode)
    assert info["candidates"] == 12
    assert filters[0].updates == [(0, None)] * info["ticks"]


def test_localization_filter_without_termination():
    env = BounceEnv(world="lab_localization_a", angles=[45.0], task="localization",
                    task_kwargs={"filter_factory": lambda o: HalvingFilter(o, start=2),
                                 "terminate_when_localized": False})
    env.reset(seed=0)
    for _ in range(5):
        _, reward, terminated, _, info = env.step(0)
        assert not terminated
    assert info["localized"] is True
    assert reward == 0.0  # nothing left to learn, no more ticks charged


@pytest.mark.parametrize("action", [True, None, "x", [object()]])
def test_continuous_actions_must_be_numbers(action):
    env = BounceEnv(action_type="continuous")
    env.reset(seed=0)
    with pytest.raises(ActionError, match="expected a number"):
        env.step(action)


def test_fixed_navigation_goal_outside_the_world_fails_at_construction():
    with pytest.raises(ConfigError, match="task_kwargs.goal"):
        BounceEnv(task="navigation", task_kwargs={"goal": {"position": [100, 100], "heading": 0}})
