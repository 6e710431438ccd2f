"""The sampled generalized cell mapping under ``physics="dynamic"`` (pymunk rigid bodies, motors,
timed turns): a bump pose of the simulator is a valid start that reads as a contact, the model
builds with every sample point starting in contact, and it is a function of its seed."""

from __future__ import annotations

import numpy as np
import pytest

from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.backends.pymunk_dynamic import BLOCKED, TRAVEL
from bounce_gym.dynamics.bump_sampler import first_bumps
from bounce_gym.dynamics.sampled_model import sampled_model
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

#: a small room with a pillar: a few dozen decision states at cells of 1 m
ROOM = World([(0, 0), (4, 0), (4, 3), (0, 3)], holes=[[(1.5, 1.2), (2.5, 1.2), (2.5, 1.8),
                                                        (1.5, 1.8)]], name="room")
RADIUS = 0.17
ANGLES = np.radians([45.0, 90.0, 135.0])
NOISE = {"type": "reliable", "r": 0.9, "eps_deg": 5}


def _dynamics(noise=None) -> dict:
    return {"world": ROOM, "backend": "pymunk", "radius": RADIUS, "step_length": 1.0,
            "noise": noise, "backend_options": {"physics": "dynamic"}}


def _sim(n: int = 1) -> BounceDynamics:
    return BounceDynamics(ROOM, n, backend="pymunk", physics="dynamic", radius=RADIUS)


def _bumped(heading: float) -> BounceDynamics:
    """A robot that drove from the room's corner area to its first bump."""
    sim = _sim()
    sim.reset(np.random.default_rng(0), np.array([[0.6, 0.5]]), np.array([heading]))
    sim.drive_to_contact()
    assert sim.state.blocked[0]
    return sim


@pytest.mark.parametrize("heading", [0.0, 0.3, 1.2, -0.7])
def test_a_bump_pose_of_the_simulator_round_trips_as_a_start(heading):
    sim = _bumped(heading)
    pose, angle = sim.state.position.copy(), sim.state.heading.copy()
    normal = sim.state.contact_normal.copy()
    # the robot rests a hair inside the wall: the overlap is real, and below the bound
    depth = RADIUS - ROOM.boundary_distance(pose)[0]
    assert 0.0 < depth <= sim.backend.start_depth
    again = _sim()
    again.reset(np.random.default_rng(1), pose, angle)  # no ConfigError
    assert again.state.blocked[0] and again.backend.phase[0] == BLOCKED
    assert again.state.contact_edge[0] == sim.state.contact_edge[0]
    np.testing.assert_allclose(again.state.contact_normal, normal, atol=1e-6)
    # both continue alike: the same bounce, the same next bump
    ticks = sim.bounce(np.array([ANGLES[1]]))
    assert again.bounce(np.array([ANGLES[1]])) == ticks
    assert again.state.clock[0] == sim.state.clock[0]
    np.testing.assert_allclose(again.state.position, sim.state.position, atol=1e-6)


def test_the_start_check_still_refuses_real_overlaps():
    with pytest.raises(ConfigError, match="contact depth"):
        _sim().reset(np.random.default_rng(0), np.array([[RADIUS * 0.99, 1.0]]),
                     np.array([0.0]))


def test_a_robot_placed_touching_what_it_faces_is_blocked_and_one_facing_away_drives():
    sim = _sim(2)
    start = np.array([[RADIUS, 1.0], [RADIUS, 2.5]])
    sim.reset(np.random.default_rng(0), start, np.array([np.pi, 0.0]))
    assert sim.state.blocked.tolist() == [True, False]
    np.testing.assert_allclose(sim.state.contact_normal[0], [1.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("noise", [None, NOISE], ids=["exact", "noise"])
def test_dynamic_model_builds_from_contacts_and_is_seeded(noise):
    model = CellModel(ROOM, 1.0, 8, robot_radius=RADIUS)
    sm = sampled_model(model, _dynamics(noise), ANGLES, samples=2, seed=5, cache=False)
    out = sm.outcomes
    assert len(out.states) >= 20
    assert (out.next_state >= 0).mean() > 0.95  # almost every sample bumps again in time
    assert (out.ticks > 0).mean() > 0.5  # most bounces leave the wall (0: a corner re-bump)
    again = sampled_model(model, _dynamics(noise), ANGLES, samples=2, seed=5, cache=False)
    for name, value in out.arrays().items():
        assert np.array_equal(value, again.outcomes.arrays()[name]), name
    # every sample point started touching a wall (within a bumper's travel: a robot that
    # braked after glancing off a corner may stand a little clear of the contact it latched)
    touch = RADIUS * (1 + TRAVEL)
    assert (ROOM.boundary_distance(out.start) <= touch).all()
    # the arrivals are starts: placed again, the robots that bumped read as blocked there (all
    # in this room; one that braked further than `TRAVEL` off a corner would not)
    arrived = np.flatnonzero(out.next_state >= 0)
    placed = _sim(len(arrived))
    placed.reset(np.random.default_rng(0), out.end[arrived], out.heading[arrived])
    assert placed.state.blocked.mean() >= 0.99
    step = sm.step(out.action[arrived], out.end[arrived], out.heading[arrived],
                   np.random.default_rng(0))
    assert (step.next_state >= 0).mean() > 0.95

def test_first_states_follow_the_reset_drive():
    model = CellModel(ROOM, 1.0, 8, robot_radius=RADIUS)
    z, point, _, clock = first_bumps(model, np.array([0.6, 0.5]), 0.3, 3,
                                     np.random.default_rng(0), _dynamics(), 40)
    sim = _bumped(0.3)
    assert (z >= 0).all()
    np.testing.assert_array_equal(point, np.repeat(sim.state.position, 3, axis=0))
    assert (clock == sim.state.clock[0]).all()
