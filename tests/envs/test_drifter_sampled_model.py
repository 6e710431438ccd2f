"""The sampled drifter GCM (generalized cell mapping by sampling of the env's own dynamics):
exact where one step moves exactly one cell, converging to the cell backend's model, time
dependence, the on-disk cache, and the planner that acts on it from the observation."""

import gymnasium as gym
import numpy as np
import pytest

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.drifters import HorizonReachPolicy, horizon_plan, reach_probability, value_iteration
from bounce_gym import model_cache as stored_models
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.envs.drifters import model_cache
from bounce_gym.envs.drifters.sampled import step_start_times
from bounce_gym.errors import ConfigError

CELL = 1000.0
SPEED = 0.25  # m/s: a step of CELL / SPEED seconds moves exactly one cell


def _one_cell_env():
    return gym.make("bounce_gym/Drifter-v0", flow="uniform",
                    flow_kwargs={"u": SPEED, "basin": "open", "shape": (6, 8), "n_layers": 2},
                    backend="continuous", rho=1.0, step_seconds=CELL / SPEED,
                    goal={"cell": (0, 3, 6)}).unwrapped


def _tv(a, b):
    return 0.5 * np.asarray(abs(a - b).sum(axis=1)).ravel()


def test_one_cell_per_step_flow_gives_the_exact_drift_where_the_exact_model_is_plain():
    env = _one_cell_env()
    exact, sampled = env.cell_model(), env.cell_model(kind="sampled", samples=8)
    interior = np.flatnonzero(~exact.boundary)
    assert len(interior) > 0
    drift, exact_drift = sampled.drift_matrix().toarray(), exact.drift_matrix().toarray()
    np.testing.assert_array_equal(drift[interior], exact_drift[interior])
    assert sampled.doubling_tv == 0.0  # every point of a cell lands in the same cell
    # the continuous env drifts after a vertical move: up = U P
    up = sampled.action_matrices()[1].toarray()
    move_up = exact.action_matrices()[1].toarray()
    np.testing.assert_array_equal(up, move_up @ drift)


def test_cell_backend_estimate_converges_to_the_exact_model():
    env = gym.make("bounce_gym/Drifter-v0", flow="two_sink").unwrapped
    exact = env.cell_model().drift_matrix()
    coarse = env.cell_model(kind="sampled", samples=100)
    fine = env.cell_model(kind="sampled", samples=3200)
    assert coarse.n_steps == fine.n_steps == 1 and not fine.vertical_then_drift
    tv_coarse, tv_fine = _tv(coarse.drift_matrix(), exact), _tv(fine.drift_matrix(), exact)
    assert tv_fine.mean() < 0.25 * tv_coarse.mean()
    assert tv_fine.max() < 0.1
    # the reported doubling change shrinks with the sample count like the true error
    assert fine.doubling_tv < 0.25 * coarse.doubling_tv
    # the exact model's own vertical moves are kept
    for a in (1, 2):
        assert (fine.action_matrices()[a] != env.cell_model().action_matrices()[a]).nnz == 0


def test_time_dependent_field_has_one_matrix_per_step_until_its_last_snapshot():
    env = gym.make("bounce_gym/Drifter-v0", backend="continuous").unwrapped
    times = step_start_times(env.options, horizon=200)
    flow_end = env.flow.time[-1]
    assert all(t < flow_end for t in times[:-1]) and times[-1] >= flow_end
    assert step_start_times(env.options, horizon=2) == times[:3][:2] + [times[2]]
    model = env.cell_model(kind="sampled", samples=4, horizon=2)
    assert model.n_steps == 3
    assert _tv(model.drift_at(0), model.drift_at(1)).mean() > 0.1  # the tide turns
    assert model.drift_at(50) is model.drift_at(2)


def test_cache_reloads_and_rebuilds_a_corrupt_or_stale_file():
    env = _one_cell_env()
    first = env.cell_model(kind="sampled", samples=4, seed=3)
    key = model_cache.drifter_model_fingerprint(env.options, 4, 3, env.core.clock_steps, 1)
    path = model_cache.cache_path(key)
    assert path.is_file()
    stamp = path.stat().st_mtime_ns
    again = _one_cell_env().cell_model(kind="sampled", samples=4, seed=3)
    assert path.stat().st_mtime_ns == stamp  # read, not rebuilt
    assert all((a != b).nnz == 0 for a, b in zip(first.drifts, again.drifts, strict=True))
    for damage in (b"not a zip file", path.read_bytes()[:100]):
        path.write_bytes(damage)
        with pytest.warns(UserWarning, match="unusable"):
            rebuilt = _one_cell_env().cell_model(kind="sampled", samples=4, seed=3)
        assert all((a != b).nnz == 0 for a, b in zip(first.drifts, rebuilt.drifts, strict=True))
    # a valid file of another model under this name is stale: rebuilt
    other = model_cache.cache_path(model_cache.drifter_model_fingerprint(env.options, 4, 4,
                                                           env.core.clock_steps, 1))
    _one_cell_env().cell_model(kind="sampled", samples=4, seed=4)
    path.write_bytes(other.read_bytes())
    with pytest.warns(UserWarning, match="does not match"):
        rebuilt = _one_cell_env().cell_model(kind="sampled", samples=4, seed=3)
    assert rebuilt.seed == 3
    header, _ = stored_models.load_cached(path, model_cache.FORMAT, key)  # the file was replaced
    assert header["seed"] == 3


@pytest.mark.parametrize("kwargs, message", [
    ({"kind": "learned"}, "kind"), ({"samples": 3, "kind": "sampled"}, "samples"),
    ({"samples": 8}, "samples: only a sampled"), ({"kind": "sampled", "refine": 0}, "refine")])
def test_bad_model_arguments_raise(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        _one_cell_env().cell_model(**kwargs)


def test_refined_model_counts_in_sub_cells_of_the_same_dynamics():
    env = _one_cell_env()
    coarse = env.cell_model(kind="sampled", samples=8)
    fine = env.cell_model(kind="sampled", samples=8, refine=3)
    assert fine.n_states == 9 * coarse.n_states
    # one cell per step moves every sub-cell to the same sub-cell one cell east, where that
    # stays on the grid (else the substeps stop at the edge: the last sub-cell)
    x, y = fine.centre(np.arange(fine.n_states))
    P = fine.drift_matrix()
    assert np.all(np.diff(P.indptr) == 1)  # every point of a sub-cell ends in one sub-cell
    ex, ey = fine.centre(P.indices)
    east = env.flow.x[-1] + CELL / 2
    inside = x + CELL < east
    assert inside.any() and (~inside).any()
    np.testing.assert_allclose(ex[inside] - x[inside], CELL)
    np.testing.assert_allclose(ex[~inside], fine.field.x[-1])
    np.testing.assert_allclose(ey, y)


def test_horizon_plan_is_at_least_as_good_as_alg_5_5_within_the_horizon():
    env = gym.make("bounce_gym/Drifter-v0", flow="two_sink", flow_kwargs={"swirl": 0.3},
                   goal={"cell": (0, 7, 20), "halo": 1}).unwrapped
    model = env.cell_model()
    goal = env.task.region.states
    plan = horizon_plan(model, goal, 30)
    alg55 = reach_probability(model, value_iteration(model, goal).policy, goal, 30)
    outside = np.setdiff1d(np.arange(model.n_states), goal)
    assert np.all(plan.values[0, outside] >= alg55[outside] - 1e-12)
    # V_0 is the reach probability of the plan: simulate its time-dependent chain
    p = np.zeros(model.n_states)
    start = outside[np.argmax(plan.values[0, outside])]
    p[start], reached = 1.0, 0.0
    stacked = model.action_matrices()
    for k in range(30):
        nxt = sum(stacked[a].T @ (p * (plan.policy[k] == a)) for a in range(3))
        reached += nxt[goal].sum()
        nxt[goal] = 0.0
        p = nxt
    assert reached == pytest.approx(plan.values[0, start])


def test_policy_acts_on_the_observation_only_and_reports_its_prediction():
    env = gym.make("bounce_gym/Drifter-v0", backend="continuous", observe_pose=True,
                   observe_fix=True)
    policy = HorizonReachPolicy(200, samples=4)
    obs, info = env.reset(seed=10_000)
    policy.reset(env)
    assert 0.0 <= policy.predicted_success(info["state"]) <= 1.0
    for _ in range(20):
        x, y, layer, steps = env.unwrapped.core.observed_pose(obs[None])
        assert env.unwrapped.cell_model().state_at_point(x, y, layer)[0] == info["state"]
        assert steps[0] == info["steps"]
        action = policy.act(obs, None)  # no info
        assert action == policy.plan.policy[info["steps"], info["state"]]
        obs, _, terminated, _, info = env.step(action)
        if terminated:
            break


def test_policy_needs_the_observed_pose():
    env = gym.make("bounce_gym/Drifter-v0", backend="continuous")
    env.reset(seed=10_000)
    with pytest.raises(ConfigError, match="observe_pose"):
        HorizonReachPolicy(200, samples=4).reset(env)


def test_sampled_model_samples_the_held_step_with_drift_after_vertical_moves():
    env = _one_cell_env()
    model = env.cell_model(kind="sampled", samples=4)
    exact: DrifterCells = env.cell_model()
    rng = np.random.default_rng(0)
    interior = np.flatnonzero(~exact.boundary & exact.legal[:, 2])
    z = int(interior[0])
    assert model.sample_one(z, DRIFT, rng) == exact.mapped[z]
    below = exact.vertical[z, 2]
    assert model.sample_one(z, 2, rng) == exact.mapped[below]
