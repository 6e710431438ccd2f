"""The tabulated bump-to-bump map of pymunk's dynamic physics (`bounce_gym.dynamics.bump_table`)
against the simulator it tabulates, its cache and its factory. One coarse table of a small room
with a pillar is built once for the module (about 2,500 nodes)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics import bump_table as bt
from bounce_gym.dynamics.boundary_pieces import BoundaryPieces
from bounce_gym.dynamics.bump_sampler import drive_from_rest, reset_drives, simulate_bumps
from bounce_gym.dynamics.bump_table import BumpMotion, bump_motion, bump_table, turn_tick_steps
from bounce_gym.dynamics.platform import physics_params
from bounce_gym.dynamics.table_check import table_error
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

ROOM = World([(0, 0), (2.5, 0), (2.5, 2), (0, 2)],
             holes=[[(1.0, 0.8), (1.4, 0.8), (1.4, 1.2), (1.0, 1.2)]], name="pillar_room")
RADIUS = 0.17
DYNAMICS = {"world": ROOM, "backend": "pymunk", "radius": RADIUS, "step_length": 1.0,
            "backend_options": {"physics": "dynamic"}}
MODEL = CellModel(ROOM, 0.5, 8, robot_radius=RADIUS)
#: the coarse resolution of the test table: a node every radius, 10° between headings
SPACING, HEADINGS = 1.0, 36


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    return bump_table(DYNAMICS, SPACING, HEADINGS, cache=tmp_path_factory.mktemp("tables"))


def test_the_table_predicts_the_simulator_on_held_out_poses(table):
    report = table_error(table, MODEL, DYNAMICS, n=80, seed=7)
    bumps, reset = report["bumps"], report["reset"]
    assert bumps["n"] >= 60 and reset["n"] >= 70
    # measured at this coarse resolution (seeds 7-9, about 80 poses each): the same decision
    # state for 94-100 % of the bumps and 92-95 % of the reset drives, the same clock for
    # 99-100 % of the bumps, within one tick for all; the bounds leave room for chance
    assert bumps["same_state"]["share"] >= 0.85
    assert reset["same_state"]["share"] >= 0.85
    assert bumps["ticks_within_1"]["share"] >= 0.95 and bumps["ticks_exact"]["share"] >= 0.85
    assert reset["ticks_within_1"]["share"] >= 0.95
    median = bumps["position_error"][0]
    assert median["q"] == 0.5 and median["value"] < 0.02  # world units (metres)


def test_cache_round_trip_and_a_corrupt_file_is_rebuilt(table, tmp_path, monkeypatch):
    first = bump_table(DYNAMICS, SPACING, HEADINGS, cache=tmp_path)
    path = tmp_path / f"{first.fingerprint}.npz"
    assert path.is_file()

    def no_build(*args):
        raise AssertionError("built again instead of read from the cache")

    with monkeypatch.context() as patch:
        patch.setattr(bt, "_build", no_build)
        again = bump_table(DYNAMICS, SPACING, HEADINGS, cache=tmp_path)
    for name in ("end", "heading", "normal", "end_piece", "seconds"):
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    assert again.lag == first.lag and again.build_seconds == first.build_seconds
    # the table does not depend on the noise: the same file serves every noise model
    noisy = dict(DYNAMICS, noise={"type": "reliable", "r": 0.5, "eps_deg": 10})
    assert bt.table_fingerprint(noisy, SPACING, HEADINGS) == first.fingerprint
    path.write_bytes(b"not a zip file")
    with pytest.warns(UserWarning, match="unusable"):
        rebuilt = bump_table(DYNAMICS, SPACING, HEADINGS, cache=tmp_path)
    np.testing.assert_array_equal(rebuilt.end_piece, first.end_piece)
    assert bump_table(DYNAMICS, SPACING, HEADINGS, cache=tmp_path).end.shape == first.end.shape


def _poses(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    z, end, heading, _ = reset_drives(MODEL, DYNAMICS, ROOM.sample_free(rng, n, RADIUS),
                                      rng.uniform(0, 2 * math.pi, n), rng, 40)
    return end[z >= 0], heading[z >= 0]


def test_lookups_are_deterministic_given_the_generator(table):
    noisy = dict(DYNAMICS, noise={"type": "reliable", "r": 0.5, "eps_deg": 10})
    motion = BumpMotion(MODEL, noisy, table)
    point, heading = _poses(30, 3)
    angles, action = np.radians([45.0, 135.0]), np.arange(len(point)) % 2
    one = motion.bumps(angles, action, point, heading, np.random.default_rng(5), 40)
    two = motion.bumps(angles, action, point, heading, np.random.default_rng(5), 40)
    other = motion.bumps(angles, action, point, heading, np.random.default_rng(6), 40)
    for name in ("next_state", "ticks", "end", "heading"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    assert not np.array_equal(one.heading, other.heading)  # the noise was drawn
    np.testing.assert_array_equal(one.start, point)


def test_a_pose_off_the_boundary_keeps_its_place(table):
    point = np.array([[1.2, 0.4], [0.17, 1.0]])  # in the open; on the left wall
    out = table.bumps(MODEL, np.array([math.pi / 2]), np.zeros(2, dtype=np.int64), point,
                      np.array([math.pi, math.pi]), np.random.default_rng(0), None, 40)
    assert out.next_state[0] == -1 and out.ticks[0] == 0
    np.testing.assert_array_equal(out.end[0], point[0])
    assert out.next_state[1] >= 0 and out.ticks[1] >= 1


def test_the_clock_is_the_turns_ticks_plus_the_drives():
    """With quarter ticks (τ = 1 s) turns take up to three ticks. A robot that drove to the
    bottom wall bumps there with several rotations: by up to 80° it still faces the wall and
    bumps again after the turn's ticks alone; by more it drives off, and its clock is the
    turn's ticks plus those of a drive from rest along its new heading — the decomposition the
    table's clock rests on."""
    fast = dict(DYNAMICS, step_length=0.25)
    rng = np.random.default_rng(0)
    first = drive_from_rest(fast, np.array([[0.6, 0.6]]), np.array([-math.pi / 2]), rng, 40)
    turn = np.radians([10.0, 60.0, 80.0, 100.0, 250.0])
    n = len(turn)
    point, heading = np.repeat(first.end, n, axis=0), np.repeat(first.heading, n)
    out = simulate_bumps(MODEL, turn, np.arange(n), point, heading, rng, fast, 200)
    turn_ticks = np.searchsorted(turn_tick_steps(physics_params(None), 1.0), turn)
    np.testing.assert_array_equal(turn_ticks, [0, 0, 1, 1, 2])
    drive = drive_from_rest(fast, point, heading + turn, rng, 200)
    np.testing.assert_array_equal(drive.clock[:3], 0)  # still facing the wall
    assert (drive.clock[3:] >= 1).all()
    np.testing.assert_array_equal(out.ticks, turn_ticks + drive.clock)


def test_the_factory_uses_the_table_only_where_it_applies(table):
    assert bump_motion(MODEL, DYNAMICS, tabulated=False).table is None
    kinematic = {"world": ROOM, "backend": "kinematic", "radius": RADIUS}
    assert bump_motion(MODEL, kinematic).table is None
    assert bump_motion(MODEL, dict(DYNAMICS, rule="specular")).table is None
    with pytest.raises(ConfigError):
        bump_motion(MODEL, kinematic, tabulated=True)
    # the simulator path returns what bump_sampler returns
    point, heading = _poses(4, 9)
    sim = bump_motion(MODEL, DYNAMICS, tabulated=False)
    out = sim.bumps(np.radians([90.0]), np.zeros(len(point), dtype=np.int64), point, heading,
                    np.random.default_rng(1), 40)
    assert len(out.next_state) == len(point)


def test_reset_drive_clocks_are_each_robots_own():
    """`drive_from_rest` reads each robot when it is blocked: a robot that reaches a wall
    early in a batch does not count the ticks the others still drive."""
    point = np.array([[0.6, 0.3], [0.6, 0.3], [2.0, 1.0]])
    heading = np.array([-math.pi / 2, 0.0, math.pi])  # 0.13 to the wall; 1.73; 0.93 then more
    together = drive_from_rest(DYNAMICS, point, heading, np.random.default_rng(0), 40)
    alone = [drive_from_rest(DYNAMICS, point[i:i + 1], heading[i:i + 1],
                             np.random.default_rng(0), 40).clock[0] for i in range(3)]
    np.testing.assert_array_equal(together.clock, alone)
    assert together.clock[0] < together.clock[1]


def test_boundary_points_project_back_to_their_arc_length():
    pieces = BoundaryPieces(ROOM, RADIUS)
    # the room's inside corners cut its ring; the pillar's ring has none: one piece
    assert pieces.n_pieces == 5
    total = 2 * (2.5 - 2 * RADIUS) + 2 * (2 - 2 * RADIUS) + 1.6 + 2 * math.pi * RADIUS
    assert pieces.length.sum() == pytest.approx(total, rel=2e-3)  # the arcs are chords
    rng = np.random.default_rng(0)
    piece = rng.integers(0, pieces.n_pieces, 500)
    s = rng.random(500) * pieces.length[piece]
    point, normal = pieces.locate(piece, s)
    near = pieces.project(point + 1e-6 * normal)
    np.testing.assert_array_equal(near.piece, piece)
    np.testing.assert_allclose(near.s, s, atol=1e-9)
    np.testing.assert_allclose(near.distance, 1e-6, rtol=1e-6)
    assert np.isinf(pieces.project(np.array([[1.2, 0.4]])).distance[0])  # far from it


def test_the_factory_builds_the_table_at_its_first_use_not_before(tmp_path, table):
    """Making a motion (an env's construction, a configuration's validation) builds nothing; its
    first use loads or builds the table, once."""
    motion = bump_motion(MODEL, DYNAMICS, spacing=SPACING, headings=HEADINGS, cache=tmp_path)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ConfigError):  # the arguments are checked when it is made
        bump_motion(MODEL, DYNAMICS, spacing=0.0, cache=tmp_path)
    assert motion.table is not None and len(list(tmp_path.glob("*.npz"))) == 1
    assert motion.table is motion.table
    np.testing.assert_array_equal(motion.table.end, table.end)
