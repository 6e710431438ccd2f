"""The sampled generalized cell mapping: exact on the cell backend, seeded, converging, cached."""

from __future__ import annotations

import math

import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.cells.sections import BumpSections
from bounce_gym.dynamics.sampled_model import default_cache, sampled_model
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import get

ANGLES = np.radians([45.0, 90.0, 135.0])


def _exact_bump_map(model: CellModel, z: int, phi: float) -> tuple[int, int]:
    """The cell model's next bump cell and the ticks driven, from bump cell z and angle φ."""
    p, k = model.decode(z)
    z = int(model.cell_id(p, (k + model.angle_bins(phi)) % model.n_bins))
    ticks = 0
    while True:
        p, k = model.decode(z)
        target = int(model.targets[k, p])
        if target < 0:
            return z, ticks
        z, ticks = int(model.cell_id(target, k)), ticks + 1


def _dynamics(world, backend: str, **extra) -> dict:
    out = {"world": world, "backend": backend, "step_length": 1.0, **extra}
    if backend == "cell":
        out["backend_options"] = {"n_bins": 8, "corner_rule": "target_only"}
    return out


def test_cell_backend_estimate_is_the_exact_bump_to_bump_map():
    world = get("lab_navigation")
    model = CellModel(world, 1.0, 8)
    sm = sampled_model(model, _dynamics(world, "cell"), ANGLES, samples=4, cache=False)
    z, a, nxt, ticks, p = sm.outcomes.transitions()
    blocked = np.flatnonzero((model.targets < 0).ravel())
    assert np.array_equal(np.unique(z), blocked)
    assert np.allclose(p, 1.0)  # one outcome per (state, angle): deterministic
    assert len(z) == len(blocked) * len(ANGLES)
    for zi, ai, ni, ti in zip(z.tolist(), a.tolist(), nxt.tolist(), ticks.tolist(),
                              strict=True):
        assert (ni, ti) == _exact_bump_map(model, zi, float(ANGLES[ai]))
    assert sm.convergence == {"tv_halves_mean": 0.0, "tv_halves_max": 0.0}


def test_kinematic_estimate_is_a_distribution_that_converges():
    world = get("lab_navigation")
    model = CellModel(world, 1.0, 8)
    sm = sampled_model(model, _dynamics(world, "kinematic"), ANGLES, samples=64, cache=False)
    out = sm.outcomes
    for matrix in out.matrices():
        rows = np.asarray(matrix.sum(axis=1)).ravel()
        assert np.allclose(rows[out.states], 1.0)  # no sample got lost in the ideal world
    # the spread-heading estimate: next states differ between samples of one state
    assert (out.transitions()[4] < 1.0).any()
    assert 0.0 < sm.convergence["tv_halves_mean"] < 0.3
    # every recorded next state is a decision state the sampler can start from
    assert set(np.unique(out.next_state).tolist()) <= set(out.states.tolist())


def test_fixed_heading_offset_keeps_headings_on_the_bins():
    world = get("lab_navigation")
    model = CellModel(world, 1.0, 8)
    sm = sampled_model(model, _dynamics(world, "kinematic"), ANGLES, samples=16, offset=0.0,
                       cache=False)
    headings = np.concatenate((sm.outcomes.heading, ))
    steps = headings / model.bin_width
    assert np.allclose(steps, np.rint(steps), atol=1e-9)


def test_bump_states_of_sections_are_their_cells():
    world = get("lab_navigation")
    model = CellModel(world, 1.0, 8)
    sections = BumpSections(model)
    cells = np.flatnonzero(sections.measure > 0)
    rng = np.random.default_rng(1)
    point, heading, normal = sections.sample(cells, 5, rng)
    assert np.array_equal(BumpStates(model).of(point, heading, normal), np.repeat(cells, 5))
    # headings face the wall they touch
    d = np.column_stack((np.cos(heading), np.sin(heading)))
    assert np.all(np.einsum("ij,ij->i", d, normal) <= 1e-12)


def test_seeded_and_cached_and_rebuilt_when_corrupt(tmp_path):
    world = get("lab_navigation")
    model = CellModel(world, 1.0, 8)
    dyn = _dynamics(world, "kinematic")
    first = sampled_model(model, dyn, ANGLES, samples=8, seed=3, cache=tmp_path)
    files = list(tmp_path.glob("*.npz"))
    assert [f.name for f in files] == [f"{first.fingerprint}.npz"]
    again = sampled_model(model, dyn, ANGLES, samples=8, seed=3, cache=tmp_path)
    fresh = sampled_model(model, dyn, ANGLES, samples=8, seed=3, cache=False)
    for name, value in first.outcomes.arrays().items():
        assert np.array_equal(value, again.outcomes.arrays()[name])
        assert np.array_equal(value, fresh.outcomes.arrays()[name])
    assert again.convergence == first.convergence
    other = sampled_model(model, dyn, ANGLES, samples=8, seed=4, cache=tmp_path)
    assert other.fingerprint != first.fingerprint
    files[0].write_bytes(b"not a zip file")
    rebuilt = sampled_model(model, dyn, ANGLES, samples=8, seed=3, cache=tmp_path)
    assert np.array_equal(rebuilt.outcomes.next_state, first.outcomes.next_state)
    assert files[0].read_bytes()[:2] == b"PK"  # replaced by a readable file


def test_stale_header_is_rebuilt(tmp_path):
    world = get("lab_navigation")
    model = CellModel(world, 1.0, 8)
    dyn = _dynamics(world, "kinematic")
    a = sampled_model(model, dyn, ANGLES, samples=4, seed=0, cache=tmp_path)
    b = sampled_model(model, dyn, ANGLES, samples=4, seed=1, cache=tmp_path)
    # put b's file under a's name: the header names another fingerprint
    (tmp_path / f"{a.fingerprint}.npz").write_bytes((tmp_path / f"{b.fingerprint}.npz").read_bytes())
    again = sampled_model(model, dyn, ANGLES, samples=4, seed=0, cache=tmp_path)
    assert np.array_equal(again.outcomes.start, a.outcomes.start)


def test_env_seam_and_default_cache_folder():
    env = BounceEnv(world="lab_navigation", backend="kinematic", task="navigation",
                    angles=[45, 90, 135])
    sm = env.unwrapped.cell_model(kind="sampled", samples=4)
    assert sm.model is env.unwrapped.cell_model()
    assert (default_cache() / f"{sm.fingerprint}.npz").is_file()
    assert env.unwrapped.cell_model(kind="sampled", samples=4) is sm
    np.testing.assert_allclose(sm.outcomes.angles, ANGLES)
    with pytest.raises(ConfigError, match="kind"):
        env.unwrapped.cell_model(kind="learned")


def test_first_states_follow_the_reset_drive():
    env = BounceEnv(world="lab_navigation", backend="kinematic", task="navigation",
                    angles=[45, 90, 135])
    sm = env.unwrapped.cell_model(kind="sampled", samples=2, cache=False)
    centre = sm.model.centres[5]
    start = {"position": centre.tolist(), "heading": math.pi / 2}
    _, _ = env.reset(seed=10_000, options={"start": start})
    state = env.unwrapped.robot_state
    z, _, _, clock = sm.first_states(centre, math.pi / 2, 3, np.random.default_rng(0))
    expected = BumpStates(sm.model).of(state.position, state.heading, state.contact_normal)
    assert np.all(z == expected[0])
    assert np.all(clock == state.clock[0])
