"""The particle belief of `bounce_gym.dynamics.particles`: Monte Carlo localization moved by the
env's own dynamics."""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics.noise import Reliable
from bounce_gym.dynamics.particles import ParticleBelief
from bounce_gym.dynamics.simulator import BounceDynamics
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import get

ANGLES = np.radians([45.0, 135.0])


def track(world_name: str, seed: int, bumps: int, noise=None, particles: int = 3000):
    """A robot from a random start bouncing with random angles, and a belief fed its clocks:
    the belief and the robot's true pose after the last bump."""
    world = get(world_name)
    model = CellModel(world, 1.0, 8, 0.0)
    dynamics = {"world": world, "backend": "kinematic", "noise": noise}
    robot = BounceDynamics(world, 1, backend="kinematic", noise=noise)
    rng = np.random.default_rng(seed)
    state = robot.reset(rng)
    robot.drive_to_contact()
    belief = ParticleBelief(model, dynamics, particles)
    belief.reset(np.random.default_rng(seed + 1), int(state.clock[0]))
    for _ in range(bumps):
        angle = float(ANGLES[rng.integers(2)])
        robot.bounce(np.array([angle]))
        belief.update(angle, int(state.clock[0]))
    truth = BumpStates(model).of(state.position, state.heading, state.contact_normal)[0]
    return belief, state, truth


@pytest.mark.parametrize(("noise", "seeds"), [(None, (1, 2, 3)),
                                               (Reliable(0.9, np.radians(5.0)), (1, 2))])
def test_the_particles_concentrate_on_the_true_pose(noise, seeds):
    for seed in seeds:  # random angles, 40 bumps
        belief, state, truth = track("lab_localization_a", seed, 40, noise)
        assert belief.most_likely == truth
        assert belief.max_mass >= 0.8  # from about 0.03 for the prior
        distance = np.hypot(*(belief.position - state.position[0]).T)
        assert np.median(distance) < 0.3


def test_the_belief_is_deterministic_given_its_generator():
    one, _, _ = track("lab_localization_a", 7, 10, particles=500)
    two, _, _ = track("lab_localization_a", 7, 10, particles=500)
    np.testing.assert_array_equal(one.states, two.states)
    np.testing.assert_array_equal(one.position, two.position)


def test_the_mass_sums_to_one_and_an_impossible_clock_redraws_the_belief():
    belief, _, _ = track("lab_localization_a", 4, 3, particles=100)
    states, mass = belief.mass()
    assert mass.sum() == pytest.approx(1.0)
    assert belief.max_mass == mass[states >= 0].max()
    belief.update(float(ANGLES[0]), 10_000)  # no drive in this world is that long
    assert belief.depletions == 1 and belief.ess == 0.0
    # drawn anew: prior contact poses bounced with the angle, at a contact, equally weighted
    assert len(belief.states) == 100 and (belief.states >= 0).all()
    assert (belief.weight == 1.0 / 100).all()
    assert (belief.previous == -1).all()  # no particle descends from the old belief


def test_backends_without_continuous_independent_drives_are_refused():
    world = get("lab_localization_a")
    with pytest.raises(ConfigError, match="not supported"):
        ParticleBelief(CellModel(world, 1.0, 8, 0.0), {"world": world, "backend": "cell"}, 10)


def test_a_reset_clock_no_prior_pose_reads_keeps_the_nearest_clock():
    """A clock after reset that no drawn start pose reproduces gives the prior of the nearest
    clock that any does (here the longest drive in the world), not an error."""
    world = get("lab_localization_a")
    model = CellModel(world, 1.0, 8, 0.0)
    belief = ParticleBelief(model, {"world": world, "backend": "kinematic"}, 200)
    belief.reset(np.random.default_rng(0), 10_000)
    assert len(belief.states) == 200 and (belief.states >= 0).all()
    assert belief.max_mass > 0
