"""The JAX kinematic env (`bounce_gym.jax.kinematic`) against the NumPy `BounceEnv` on the
kinematic backend: same starts, goals and actions give the same observations, rewards, ends and
positions (1e-9) under float64, over more than 10,000 steps across maps."""

from __future__ import annotations

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the ids)
from bounce_gym.errors import ConfigError
from bounce_gym.jax import make
from bounce_gym.jax.kinematic import KinematicState
from bounce_gym.worlds import zoo
from bounce_gym.worlds.generators import random_star_polygon

EPISODES = 10
STEPS = 256
STAR = random_star_polygon(np.random.default_rng(7), n_vertices=12, name="star_test")

#: (id, options) compared along whole trajectories: lab_navigation v0 as registered; two_rooms
#: with a disk robot, the papers' plan-cost reward and the privileged pose; non-axis-aligned
#: walls (the heptagon with the sparse reward and continuous actions; a generated star with a
#: disk robot meeting reflex corners)
TRAJECTORIES = {
    "lab_navigation": ("bounce_gym/BounceNavigation-v0", {}),
    "two_rooms": ("bounce_gym/BounceNavigation-v0",
                  {"world": "two_rooms", "robot_radius": 0.3, "privileged": True,
                   "task_kwargs": {"reward": "plan_cost"}}),
    "heptagon": ("bounce_gym/BounceNavigation-v0",
                 {"world": "heptagon", "step_length": 20.0, "task_kwargs": {"reward": "sparse"},
                  "action_type": "continuous", "angle_range": (30.0, 300.0)}),
    "star": ("bounce_gym/Bounce-v0",
             {"world": STAR, "robot_radius": 5.0, "step_length": 10.0, "history": 2,
              "action_type": "continuous", "angle_range": (20.0, 340.0)}),
}
#: (id, options) compared step by step, each JAX step from the NumPy env's state: the
#: boundary-relative rules. The fixed and monotonic ones are chaotic here (two NumPy runs whose
#: start positions differ by 1e-11 part by more than 1e-9 within tens of bounces,
#: `test_boundary_rules_are_chaotic`), so rounding-level differences grow along a trajectory
#: whatever the implementation
STEPWISE = {
    "star_monotonic": ("bounce_gym/Bounce-v0",
                       {"world": STAR, "robot_radius": 5.0, "step_length": 10.0, "history": 2,
                        "bounce_rule": "monotonic", "action_type": "continuous"}),
    "two_rooms_specular": ("bounce_gym/Bounce-v0",
                           {"world": "two_rooms", "robot_radius": 0.3,
                            "bounce_rule": "specular"}),
    "grid_fixed": ("bounce_gym/Bounce-v0",
                   {"world": "grid_10x10", "robot_radius": 0.25, "bounce_rule": "fixed",
                    "history": 1}),
}
CASES = {**TRAJECTORIES, **STEPWISE}


def _rollout(env, params, starts, goals, actions):
    """Per episode: the reset's observation and position, then per step the observation,
    position, reward and termination, by `reset_to` and a scan of `step_env` (no auto-reset)."""
    key = jax.random.PRNGKey(0)

    def episode(start, goal, acts):
        obs0, state = env.reset_to(params, start[:2], start[2], goal[:2], goal[2])

        def body(state, action):
            obs, state, reward, _, info = env.step_env(key, state, action, params)
            return state, (obs, state.position, reward, info["terminated"])

        return (obs0, state.position), jax.lax.scan(body, state, acts)[1]

    return jax.device_get(jax.jit(jax.vmap(episode))(starts, goals, actions))


def _numpy_rollout(numpy_env, start, goal, actions, has_goal: bool):
    pose = lambda p: {"position": p[:2].tolist(), "heading": float(p[2])}  # noqa: E731
    options = {"start": pose(start), **({"goal": pose(goal)} if has_goal else {})}
    obs, info = numpy_env.reset(seed=0, options=options)
    first = (obs, info["position"])
    steps = []
    for action in actions:
        obs, reward, terminated, _, info = numpy_env.step(action)
        steps.append((obs, info["position"], reward, terminated))
        if terminated:
            break
    return first, steps


def _setup(name):
    env_id, options = CASES[name]
    env, _ = make(env_id, **options)
    numpy_env = gym.make(env_id, **options).unwrapped
    world = numpy_env.options.world
    rng = np.random.default_rng(2024)
    poses = np.concatenate([world.sample_free(rng, 2 * EPISODES, numpy_env.options.robot_radius),
                            rng.uniform(0, 2 * np.pi, (2 * EPISODES, 1))], axis=1)
    if env.continuous:
        actions = rng.uniform(-1, 1, (EPISODES, STEPS, 1)).astype(np.float32)
    else:
        actions = rng.integers(0, env.action_space().n, (EPISODES, STEPS)).astype(np.int64)
    return env, numpy_env, poses[:EPISODES], poses[EPISODES:], actions


def _numpy_action(env, action):
    return action if env.continuous else int(action)


@pytest.fixture(scope="module", params=sorted(TRAJECTORIES))
def trajectories(request):
    """(case, number of steps compared, worst position gap) after asserting agreement."""
    name = request.param
    env, numpy_env, starts, goals, actions = _setup(name)
    with jax.enable_x64(True):
        params = env.default_params
        assert params.walls.ax.dtype == jnp.float64
        (obs0, pos0), (obs, pos, rewards, ends) = _rollout(env, params, starts, goals, actions)
    has_goal = env.task.name == "navigation"
    count, worst, flips = 0, 0.0, 0
    cell = _cell_of(numpy_env)
    for e in range(EPISODES):
        np_actions = [_numpy_action(env, a) for a in actions[e]]
        first, steps = _numpy_rollout(numpy_env, starts[e], goals[e], np_actions, has_goal)
        np.testing.assert_array_equal(obs0[e], first[0])
        np.testing.assert_allclose(pos0[e], first[1], rtol=0, atol=1e-9)
        for t, (o, p, r, end) in enumerate(steps):
            where = f"{name}: episode {e} step {t}"
            np.testing.assert_allclose(obs[e, t], o, rtol=0, atol=1e-6, err_msg=where)
            np.testing.assert_allclose(pos[e, t], p, rtol=0, atol=1e-9, err_msg=where)
            # Φ is read in the grid cell holding the robot, and a robot resting on a wall along
            # a grid line lies in either cell by rounding (XLA fuses multiply-adds, NumPy does
            # not): where the JAX and NumPy positions (1e-13 apart) fall in different cells, this
            # step's and the next one's shaping may differ by a step of Φ (counted, bounded)
            flip = cell(pos[e, t]) != cell(p) or (t > 0 and cell(pos[e, t - 1])
                                                  != cell(steps[t - 1][1]))
            off = abs(float(rewards[e, t]) - r) > 1e-6
            assert flip or not off, where
            flips += off
            assert bool(ends[e, t]) == end, where
            worst = max(worst, float(np.abs(pos[e, t] - p).max()))
        count += len(steps)
    return name, count, worst, flips


def _cell_of(numpy_env):
    """The grid cell of Φ (the ``progress`` reward's geodesic grid) holding a point."""
    size = numpy_env.options.step_length
    origin = np.asarray(numpy_env.options.world.bounds[:2])
    return lambda p: tuple(np.floor((np.asarray(p) - origin) / size).astype(int))


def test_jax_kinematic_trajectories_equal_numpy_ones(trajectories):
    name, count, worst, flips = trajectories
    assert flips <= 0.05 * count
    # the free task runs every step; navigation ends episodes at their goals
    assert count >= (EPISODES * STEPS if TRAJECTORIES[name][0] == "bounce_gym/Bounce-v0"
                     else 300)
    assert worst <= 1e-9


def _numpy_steps(env, numpy_env, start, actions):
    """The NumPy env's state before each step (as a JAX `KinematicState` of the free task) and
    the observation and position after it."""
    numpy_env.reset(seed=0, options={"start": {"position": start[:2].tolist(),
                                               "heading": float(start[2])}})
    core = numpy_env.core
    before, after = [], []
    for t, action in enumerate(actions):
        state = core.state
        before.append((state.position[0].copy(), float(state.heading[0]),
                       state.contact_normal[0].copy(), int(state.contact_edge[0]),
                       int(state.clock[0]), int(state.ticks), int(state.bumps[0]), t,
                       float(core.last_angle[0]), core.history[0].copy()))
        obs, _, _, _, info = numpy_env.step(_numpy_action(env, action))
        after.append((obs, info["position"]))
    return before, after


@pytest.mark.parametrize("name", sorted(STEPWISE))
def test_jax_kinematic_steps_equal_numpy_steps(name):
    env, numpy_env, starts, _, actions = _setup(name)
    before, after = [], []
    for e in range(EPISODES):
        b, a = _numpy_steps(env, numpy_env, starts[e], actions[e])
        before += b
        after += a
    columns = [np.array(c) for c in zip(*before, strict=True)]
    with jax.enable_x64(True):
        params = env.default_params
        i32 = lambda c: jnp.asarray(c, jnp.int32)  # noqa: E731
        states = KinematicState(
            position=jnp.asarray(columns[0]), heading=jnp.asarray(columns[1]),
            normal=jnp.asarray(columns[2]), edge=i32(columns[3]), clock=i32(columns[4]),
            ticks=i32(columns[5]), bumps=i32(columns[6]), steps=i32(columns[7]),
            last_angle=jnp.asarray(columns[8]), history=jnp.asarray(columns[9], jnp.float32),
            task=())
        step = jax.vmap(env.step_env, in_axes=(None, 0, 0, None))
        obs, moved, _, _, _ = jax.device_get(jax.jit(step)(
            jax.random.PRNGKey(0), states, jnp.asarray(actions.reshape(len(before), -1)
                                                       .squeeze(-1) if not env.continuous
                                                       else actions.reshape(len(before), 1)),
            params))
    assert len(before) >= EPISODES * STEPS
    np.testing.assert_allclose(obs, np.array([o for o, _ in after]), rtol=0, atol=1e-6)
    np.testing.assert_allclose(moved.position, np.array([p for _, p in after]), rtol=0,
                               atol=1e-9)


def test_boundary_rules_are_chaotic():
    """Why `STEPWISE` compares single steps: NumPy against NumPy from start positions 1e-11
    apart (about 1e-13 of the map's size, the size of a step's rounding differences) part by
    more than 1e-9."""
    env, numpy_env, starts, _, actions = _setup("star_monotonic")
    ends = []
    for shift in (0.0, 1e-11):
        numpy_env.reset(seed=0, options={"start": {"position": (starts[0, :2] + shift).tolist(),
                                                   "heading": float(starts[0, 2])}})
        ends.append([numpy_env.step(a)[4]["position"] for a in actions[0]])
    gap = np.abs(np.array(ends[0]) - np.array(ends[1])).max(axis=1)
    assert gap[0] < 1e-9 < gap.max()


@pytest.fixture(scope="module")
def navigation():
    return make("bounce_gym/BounceNavigation-v0")


def test_vmapped_steps_equal_steps_one_env_at_a_time(navigation):
    env, params = navigation
    n, steps = 64, 12
    keys = jax.random.split(jax.random.PRNGKey(3), n)
    obs, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    step = jax.jit(env.step)
    batched = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    one_states = [jax.tree.map(lambda x, i=i: x[i], states) for i in range(n)]
    rng = np.random.default_rng(5)
    for t in range(steps):
        actions = jnp.asarray(rng.integers(0, 3, n), jnp.int32)
        step_keys = jax.random.split(jax.random.PRNGKey(100 + t), n)
        obs, states, rewards, dones, _ = batched(step_keys, states, actions, params)
        for i in range(n):
            o, one_states[i], r, d, _ = step(step_keys[i], one_states[i], actions[i], params)
            np.testing.assert_allclose(np.asarray(obs[i]), np.asarray(o), rtol=0, atol=1e-6)
            np.testing.assert_allclose(np.asarray(states.position[i]),
                                       np.asarray(one_states[i].position), rtol=0, atol=1e-5)
            assert abs(float(rewards[i]) - float(r)) <= 1e-5
            assert bool(dones[i]) == bool(d)


def test_random_starts_lie_in_the_free_space_in_contact(navigation):
    env, params = navigation
    world = env.options.world
    keys = jax.random.split(jax.random.PRNGKey(11), 2000)
    _, states = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(keys, params)
    position = np.asarray(states.position, dtype=np.float64)
    # every reset ends against a wall, within the contact tolerance (float32's, here)
    assert world.boundary_distance(position).max() <= float(params.contact_tol)
    assert world.contains(position + 1e-3 * np.asarray(states.normal)).all()
    goals = np.asarray(states.task.goal_position, dtype=np.float64)
    assert world.contains(goals, 0.0).all()
    # uniform over the free space: the share of goals in the left half is the NumPy draw's
    reference = world.sample_free(np.random.default_rng(0), 20_000, 0.0)
    left, expected = np.mean(goals[:, 0] < 7.0), np.mean(reference[:, 0] < 7.0)
    assert abs(left - expected) < 4 * np.sqrt(expected * (1 - expected) / len(goals)) + 0.005


@pytest.mark.parametrize("options, words", [
    ({"task": "coverage"}, "task 'coverage'"),
    ({"bounce_rule": "nilles_relative"}, "bounce_rule 'nilles_relative'"),
    ({"noise": {"type": "interval", "lo_deg": -5.0, "hi_deg": 5.0}}, "actuation noise"),
])
def test_options_without_a_kinematic_jax_env_are_refused(options, words):
    with pytest.raises(ConfigError, match=words):
        make("bounce_gym/Bounce-v0", **options)


def test_the_library_leaves_float32_alone():
    env, params = make("bounce_gym/Bounce-v0", world=zoo.get("lab_navigation"))
    assert params.walls.ax.dtype == jnp.float32
    obs, state = env.reset(jax.random.PRNGKey(0), params)
    assert obs.dtype == jnp.float32 and state.position.dtype == jnp.float32
