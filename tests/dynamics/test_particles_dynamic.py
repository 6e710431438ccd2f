"""The particle belief of `bounce_gym.dynamics.particles` on pymunk's dynamic physics (rigid
bodies, motors, turns that take time): particles kept as bump poses and moved through the
simulator itself (`bump_motion(..., tabulated=False)`; the tabulated map, the default there, is
pinned against the simulator in test_bump_table.py)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.bump_sampler import simulate_bumps
from bounce_gym.dynamics.bump_table import bump_motion
from bounce_gym.dynamics.particles import ParticleBelief
from bounce_gym.worlds import World

#: a small room with a pillar (as in test_sampled_dynamic.py)
ROOM = World([(0, 0), (4, 0), (4, 3), (0, 3)], holes=[[(1.5, 1.2), (2.5, 1.2), (2.5, 1.8),
                                                        (1.5, 1.8)]], name="room")
RADIUS = 0.17
ANGLES = np.radians([45.0, 135.0])
START, HEADING = np.array([[0.6, 0.5]]), np.array([0.3])
DYNAMICS = {"world": ROOM, "backend": "pymunk", "radius": RADIUS, "step_length": 1.0,
            "backend_options": {"physics": "dynamic"}}
MODEL = CellModel(ROOM, 1.0, 8, robot_radius=RADIUS)
#: the simulator, not the table
SIMULATOR = bump_motion(MODEL, DYNAMICS, tabulated=False)


def follow(seed: int, bumps: int, particles: int = 24, jitter: float | None = None):
    """A robot from a known start bouncing with random angles, and a belief started at the
    same pose fed its clocks: the belief, the robot's state, and its true decision state."""
    robot = BounceDynamics(ROOM, 1, backend="pymunk", physics="dynamic", radius=RADIUS)
    rng = np.random.default_rng(seed)
    state = robot.reset(rng, START, HEADING)
    robot.drive_to_contact()
    belief = ParticleBelief(MODEL, DYNAMICS, particles, jitter=jitter, motion=SIMULATOR)
    belief.reset_at(np.random.default_rng(seed + 1), np.repeat(START, particles, axis=0),
                    np.repeat(HEADING, particles))
    for _ in range(bumps):
        angle = float(ANGLES[rng.integers(2)])
        robot.bounce(np.array([angle]))
        belief.update(angle, int(state.clock[0]))
    truth = BumpStates(MODEL).of(state.position, state.heading, state.contact_normal)[0]
    return belief, state, truth


def test_without_noise_the_belief_follows_the_true_pose():
    belief, state, truth = follow(3, 6, jitter=0.0)
    assert belief.depletions == 0
    # every particle is the robot itself: same start, no noise, no roughening
    np.testing.assert_allclose(belief.position, np.repeat(state.position, belief.n, axis=0),
                               atol=1e-9)
    assert belief.most_likely == truth and belief.max_mass == pytest.approx(1.0)
    # with the default roughening the true pose's state keeps the mass
    belief, state, truth = follow(3, 6)
    assert belief.depletions == 0
    assert belief.most_likely == truth and belief.max_mass >= 0.5


def test_resampling_keeps_the_poses_exact():
    belief, _, _ = follow(4, 2)
    before = np.column_stack((belief.position, belief.heading, belief.states))
    weight = np.zeros(belief.n)
    weight[[1, 5]] = [0.25, 0.75]
    belief._resample(weight)
    after = np.column_stack((belief.position, belief.heading, belief.states))
    # every particle is now exactly one of the two that had weight, in proportion
    rows = [np.flatnonzero((after == before[i]).all(axis=1)) for i in (1, 5)]
    assert len(rows[0]) + len(rows[1]) == belief.n and len(rows[1]) == 3 * len(rows[0])
    assert (belief.weight == 1.0 / belief.n).all()


def test_the_belief_is_deterministic_given_its_generator():
    one, _, _ = follow(5, 3, particles=16)
    two, _, _ = follow(5, 3, particles=16)
    for name in ("position", "heading", "states", "weight"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    # the global prior too, and the expected entropies that leave the generator alone
    for belief in (one, two):
        belief.reset(np.random.default_rng(9), clock=3)
        belief.expected_entropy(ANGLES)
        belief.update(float(ANGLES[1]), 3)
    for name in ("position", "heading", "states", "weight"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))


def test_the_localization_task_builds_with_particles_on_dynamic_physics():
    env = gym.make("bounce_gym/BounceLocalization-v0", world=ROOM, backend="pymunk",
                   physics="dynamic", robot_radius=RADIUS, angles=[45, 135],
                   noise={"type": "reliable", "r": 0.9, "eps_deg": 5}, max_episode_steps=3,
                   task_kwargs={"filter_factory": "particles", "particles": 16})
    _, info = env.reset(seed=10_000)
    for _ in range(3):
        _, _, terminated, truncated, info = env.step(0)
    assert 0.0 < info["belief_mass"] <= 1.0 and info["candidates"] >= 1


def test_a_placed_bump_pose_continues_as_the_robot_on_the_lab_map():
    """The particle motion model is exact only if a robot re-placed at its bump pose continues
    as the robot does; on lab_localization_a, noise-free, the 4th bump of this robot differs."""
    env = gym.make("bounce_gym/BounceLocalization-v0", backend="pymunk", physics="dynamic",
                   angles=[45, 135])
    dynamics = dict(env.unwrapped.options.robot_dynamics)
    model = env.unwrapped.cell_model()
    params = {k: v for k, v in dynamics.items() if k != "world"}
    robot = BounceDynamics(dynamics["world"], 1, **params)
    rng = np.random.default_rng(2)
    state = robot.reset(rng)
    robot.drive_to_contact()
    for _ in range(4):
        angle = float(ANGLES[rng.integers(2)])
        out = simulate_bumps(model, np.array([angle]), np.zeros(1, dtype=np.int64),
                             state.position.copy(), state.heading.copy(),
                             np.random.default_rng(0), dynamics, 200)
        robot.bounce(np.array([angle]))
        assert int(out.ticks[0]) == int(state.clock[0])
        np.testing.assert_allclose(out.end, state.position, atol=1e-3)
