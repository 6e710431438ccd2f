"""Coverage by mixing bouncing policies (issue 5): `baselines.coverage`.

Sources: Alam, Bobadilla & Shell 2017, Sec. III-C (Coverage Problem), Sec. IV-C (Alg. 3, Eq. 4–5)
and Sec. V-C (Table I); thesis §3.4.3 (Eq. 3.7–3.8) and §3.5.3 (Table 3.1); choices where the
paper is open: docs/choices/navigation_coverage.md.
The Table I geometry is unpublished: ``lab_complex`` is a reconstruction with the paper's 183 free
positions, so only structural and qualitative properties are asserted; the numbers are printed
(``pytest -s``).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import minimize

from baselines.coverage import (
    MAX_EXACT,
    MixturePolicy,
    coverage_mixture,
    mixture_residual,
    optimal_mixture,
    policy_distributions,
    target_vector,
    to_grid,
)
from baselines.policy import FixedAnglePolicy
from bounce_gym.cells import CellModel
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import get, world_from_grid

#: Table I / Table 3.1 (Alam, Bobadilla & Shell 2017, Sec. V-C; thesis §3.5.3): Φ, ε, r and the
#: paper's α.
PHI_DEG = (30.0, 75.0, 315.0)
EPS_DEG, RELIABILITY = 5.0, 0.8
PAPER_ALPHA = np.array([0.22138172, 0.28005791, 0.49856037])
PHI_NAMES = tuple(f"{phi:g}°" for phi in PHI_DEG)
ENV_KWARGS = dict(world="lab_complex", task="coverage", backend="cell", cell_bins=360,
                  angles=list(PHI_DEG), noise={"type": "reliable", "r": RELIABILITY,
                                               "eps_deg": EPS_DEG}, step_mode="bounce")


@pytest.fixture(scope="module")
def lab() -> CellModel:
    return CellModel(get("lab_complex"), n_bins=360)


@pytest.fixture(scope="module")
def table1(lab) -> dict[str, np.ndarray]:
    """A over cells and over positions for the Table I setting (three GCMs at 65 880 cells)."""
    A = policy_distributions(lab, np.radians(PHI_DEG), math.radians(EPS_DEG), RELIABILITY)
    return {"cells": A, "positions": A.reshape(lab.n_bins, lab.n_positions, 3).sum(axis=0)}


def random_problem(rng: np.random.Generator, n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Random distributions as columns and a random target distribution."""
    A = rng.random((n, m)) ** 3
    A /= A.sum(axis=0)
    b = rng.random(n)
    return A, b / b.sum()


def slsqp_reference(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """An independent solve of Eq. 5 with scipy's SLSQP on the raw (n, m) problem."""
    w = 1.0 / float(np.max(A)) ** 2
    res = minimize(lambda a: w * float(np.sum((A @ a - b) ** 2)), np.full(A.shape[1], 0.5),
                   jac=lambda a: w * 2.0 * A.T @ (A @ a - b), method="SLSQP",
                   bounds=[(0.0, None)] * A.shape[1],
                   constraints=[{"type": "eq", "fun": lambda a: a.sum() - 1.0}],
                   options={"ftol": 1e-16, "maxiter": 2000})
    assert res.success, res.message
    return res.x


def check_valid(res, m: int) -> None:
    """Eq. 5 (docs/choices/navigation_coverage.md, "Solving Eq. 5 exactly"): α >= 0, Σ α = 1, and the KKT certificate
    holds."""
    assert res.alpha.shape == (m,)
    assert np.all(res.alpha >= 0)
    assert res.alpha.sum() == pytest.approx(1.0, abs=1e-12)
    assert set(res.support) == set(np.flatnonzero(res.alpha > 0).tolist())
    scale = abs(res.multiplier) + 2 * np.linalg.norm(res.A, 2) * np.linalg.norm(res.b)
    assert np.all(res.dual >= -1e-9 * scale)  # μ >= 0 off the support
    assert res.residual == pytest.approx(mixture_residual(res.A, res.b, res.alpha), rel=1e-12)


# -- the solver (docs/choices/navigation_coverage.md, "Solving Eq. 5 exactly") ----------------------------------------
@pytest.mark.parametrize("n, m", [(5, 2), (40, 3), (7, 7), (30, 5), (4, 6), (200, 8)])
def test_solution_is_feasible_and_beats_vertices_and_random_mixtures(n, m):
    rng = np.random.default_rng(100 * n + m)
    for _ in range(5):
        A, b = random_problem(rng, n, m)
        res = optimal_mixture(A, b)
        check_valid(res, m)
        vertex = np.array([mixture_residual(A, b, e) for e in np.eye(m)])
        np.testing.assert_allclose(res.vertex_residuals, vertex, rtol=1e-12)
        assert np.all(res.residual <= vertex + 1e-15)
        # no feasible α does better: 2000 random points of the simplex and its faces
        trials = rng.dirichlet(np.full(m, 0.3), 2000)
        trials[rng.random(trials.shape) < 0.3] = 0.0
        trials = trials[trials.sum(axis=1) > 0]
        trials /= trials.sum(axis=1, keepdims=True)
        others = np.sum((trials @ A.T - b) ** 2, axis=1)
        assert res.residual <= others.min() * (1 + 1e-12)


@pytest.mark.parametrize("m", [2, 3, 5])
def test_target_equal_to_one_policy_gives_that_vertex(m):
    rng = np.random.default_rng(m)
    A, _ = random_problem(rng, 50, m)
    for k in range(m):
        res = optimal_mixture(A, A[:, k].copy())
        np.testing.assert_array_equal(res.alpha, np.eye(m)[k])
        assert res.support == (k,)
        assert res.residual == pytest.approx(0.0, abs=1e-30)


def test_target_equal_to_a_table1_policy_gives_that_vertex(table1):
    for space, A in table1.items():
        for k in range(3):
            res = optimal_mixture(A, A[:, k].copy())
            np.testing.assert_array_equal(res.alpha, np.eye(3)[k], err_msg=space)


@pytest.mark.parametrize("m", [2, 3, 4, 6])
def test_planted_mixture_is_recovered(m):
    rng = np.random.default_rng(10 + m)
    A, _ = random_problem(rng, 60, m)
    assert np.linalg.matrix_rank(A) == m
    for zeros in (0, 1, m - 1):  # interior, on a face, a vertex
        alpha = rng.dirichlet(np.ones(m))
        alpha[rng.permutation(m)[:zeros]] = 0.0
        alpha /= alpha.sum()
        res = optimal_mixture(A, A @ alpha)
        np.testing.assert_allclose(res.alpha, alpha, rtol=0, atol=1e-8)
        assert res.support == tuple(np.flatnonzero(alpha > 0).tolist())


def test_planted_mixture_on_table1_columns(table1):
    """Recovery at the real scale: A = the three π_i over 65 880 cells (full column rank)."""
    A = table1["cells"]
    assert np.linalg.matrix_rank(A) == 3
    alpha = np.array([0.2, 0.3, 0.5])
    res = optimal_mixture(A, A @ alpha)
    np.testing.assert_allclose(res.alpha, alpha, rtol=0, atol=1e-8)


@pytest.mark.parametrize("seed", range(6))
def test_agrees_with_slsqp(seed):
    rng = np.random.default_rng(seed)
    n, m = [(30, 3), (12, 4), (80, 5), (6, 3), (25, 6), (100, 2)][seed]
    A, b = random_problem(rng, n, m)
    res = optimal_mixture(A, b)
    ref = slsqp_reference(A, b)
    ref_residual = mixture_residual(A, b, ref)
    assert res.residual <= ref_residual * (1 + 1e-9)
    assert res.residual == pytest.approx(ref_residual, rel=1e-6)
    np.testing.assert_allclose(res.alpha, ref, atol=1e-4)  # the optimum is unique: rank A = m
    # the module's own SLSQP path agrees too
    np.testing.assert_allclose(optimal_mixture(A, b, method="slsqp").alpha, res.alpha, atol=1e-4)


def test_rank_deficient_a_keeps_the_optimal_residual():
    """Duplicate and dependent columns: the minimiser is not unique but the residual is."""
    rng = np.random.default_rng(7)
    A, b = random_problem(rng, 20, 3)
    A = np.column_stack([A, A[:, 0], 0.5 * (A[:, 1] + A[:, 2])])
    res = optimal_mixture(A, b)
    check_valid(res, 5)
    assert res.residual == pytest.approx(optimal_mixture(A[:, :3], b).residual, rel=1e-9)
    assert res.residual <= mixture_residual(A, b, slsqp_reference(A, b)) * (1 + 1e-9)


def test_fewer_rows_than_policies():
    """n < m (more policies than cells) is a valid problem."""
    A = np.array([[1.0, 0.0, 0.5, 0.2], [0.0, 1.0, 0.5, 0.8]])
    res = optimal_mixture(A, np.array([0.3, 0.7]))
    check_valid(res, 4)
    assert res.residual == pytest.approx(0.0, abs=1e-20)


@pytest.mark.parametrize("A, b, match", [
    (np.ones(3), np.ones(3), "2-D"),
    (np.ones((0, 2)), np.ones(0), "2-D"),
    (np.ones((3, 0)), np.ones(3), "2-D"),
    (np.ones((3, 2)), np.ones(4), "shape"),
    (np.ones((3, 2)), np.ones((3, 1)), "shape"),
    (np.array([[1.0, np.nan], [0.0, 1.0]]), np.ones(2), "finite"),
    (np.eye(2), np.array([np.inf, 0.0]), "finite"),
    ([["a", "b"]], [1.0], "numeric"),
])
def test_bad_problems_raise(A, b, match):
    with pytest.raises(ConfigError, match=match):
        optimal_mixture(A, b)


def test_bad_method_and_too_many_policies_raise():
    with pytest.raises(ConfigError, match="method"):
        optimal_mixture(np.eye(2), np.ones(2) / 2, method="cvxpy")
    m = MAX_EXACT + 1
    with pytest.raises(ConfigError, match="slsqp"):
        optimal_mixture(np.eye(m), np.ones(m) / m)
    res = optimal_mixture(np.eye(m), np.ones(m) / m, method="slsqp")
    np.testing.assert_allclose(res.alpha, np.ones(m) / m, atol=1e-6)


# -- Alg. 3 and the targets (Sec. IV-C; docs/choices/navigation_coverage.md, "Coverage over cells or over positions")
def test_policy_distributions_are_limiting_distributions():
    model = CellModel(world_from_grid(np.ones((4, 5), dtype=bool)), n_bins=8)
    angles = np.radians([90.0, 135.0])
    A = policy_distributions(model, angles, math.radians(45), 0.6)
    assert A.shape == (model.n_cells, 2)
    assert np.all(A >= 0)
    np.testing.assert_allclose(A.sum(axis=0), 1.0, atol=1e-12)
    for i, phi in enumerate(angles):  # stationary (π P = π) from a start-anywhere Cesàro limit
        P = model.transition_matrix(phi, math.radians(45), 0.6)
        np.testing.assert_allclose(A[:, i] @ P, A[:, i], atol=1e-12)
    pos = policy_distributions(model, angles, math.radians(45), 0.6, space="positions")
    np.testing.assert_allclose(pos, A.reshape(8, model.n_positions, 2).sum(axis=0), atol=1e-15)
    with pytest.raises(ConfigError, match="space"):
        policy_distributions(model, angles, 0.0, 1.0, space="grid")
    with pytest.raises(ConfigError, match="angles"):
        policy_distributions(model, [], 0.0, 1.0)
    with pytest.raises(ConfigError, match="multiple"):  # degrees by mistake: not whole bins
        policy_distributions(model, [90.0], 0.0, 1.0)


def test_targets_and_grids(lab):
    uniform_cells = target_vector(lab, None, "cells")
    assert uniform_cells.shape == (65880,) and uniform_cells.sum() == pytest.approx(1.0)
    grid = lab.free / lab.free.sum()
    np.testing.assert_allclose(target_vector(lab, grid, "positions"), np.full(183, 1 / 183))
    np.testing.assert_allclose(target_vector(lab, grid, "cells"), uniform_cells)
    np.testing.assert_allclose(to_grid(lab, np.full(183, 1 / 183)), grid)
    np.testing.assert_allclose(to_grid(lab, uniform_cells), grid)
    blocked = np.zeros(lab.free.shape)
    blocked[~lab.free] = 1.0
    with pytest.raises(ConfigError, match="blocked"):
        target_vector(lab, blocked, "positions")
    with pytest.raises(ConfigError, match="shape"):
        target_vector(lab, np.ones(7), "cells")
    with pytest.raises(ConfigError, match=">= 0"):
        target_vector(lab, -np.ones(183), "positions")


# -- Table I on the lab_complex reconstruction (Sec. V-C; thesis §3.5.3) ------------------------
def test_table1_setting(lab, table1):
    assert lab.n_positions == 183 and lab.n_cells == 65880  # Sec. V-C
    A = table1["cells"]
    assert np.all(A >= 0)
    np.testing.assert_allclose(A.sum(axis=0), 1.0, atol=1e-9)
    res = optimal_mixture(A, target_vector(lab, None, "cells"))
    pos = coverage_mixture(lab, np.radians(PHI_DEG), math.radians(EPS_DEG), RELIABILITY,
                           space="positions")  # the convenience: Alg. 3 then Eq. 5
    np.testing.assert_allclose(pos.A, table1["positions"], atol=1e-15)
    check_valid(res, 3)
    check_valid(pos, 3)
    print("\nTable I (lab_complex reconstruction, 360 bins, ε = 5°, r = 0.8, uniform b)")
    print(f"{'φ':>6} {'paper α':>10} {'ours (cells)':>13} {'ours (positions)':>17}")
    for i, phi in enumerate(PHI_DEG):
        print(f"{phi:>5g}° {PAPER_ALPHA[i]:>10.8f} {res.alpha[i]:>13.8f} {pos.alpha[i]:>17.8f}")
    print(f"residual ‖Aα−b‖² cells {res.residual:.6g} (vertices "
          f"{np.array2string(res.vertex_residuals, precision=6)}), positions {pos.residual:.6g}")
    assert PAPER_ALPHA.sum() == pytest.approx(1.0, abs=1e-8)  # Table I's α sums to 1
    # the qualitative picture of Table I holds on the reconstruction: α is largest for 315° ...
    assert int(np.argmax(res.alpha)) == 2
    # ... and so does the paper's whole ordering 315° > 75° > 30° (over cells, as in the paper)
    assert res.alpha[2] > res.alpha[1] > res.alpha[0] > 0
    # every policy is used over cells: the mixture strictly beats every single policy
    assert res.support == (0, 1, 2)
    assert np.all(res.residual < res.vertex_residuals)
    # over positions the optimum differs (30° drops out): the two spaces are different problems
    assert pos.support == (1, 2)
    assert pos.dual[0] > 0


# -- the mixture in the env (docs/choices/navigation_coverage.md, "The mixture's coverage is the model A α") --------
def fake_env(n_actions: int = 3) -> SimpleNamespace:
    return SimpleNamespace(action_space=SimpleNamespace(n=n_actions))


def drive(policy, steps: int, ticks_per_bump=(1, 1, 1)) -> list[int]:
    """Call ``act`` as a bounce-mode env would; policy i spends ``ticks_per_bump[i]`` ticks."""
    policy.reset(fake_env())
    ticks, actions = 0, []
    for bumps in range(steps):
        a = policy.act(None, {"bumps": bumps, "ticks": ticks})
        actions.append(a)
        ticks += ticks_per_bump[a]
    return actions


def test_mixture_policy_schedules():
    alpha = np.array([0.2, 0.0, 0.8])
    # time schedule: epochs of 5 bumps, policy 0 spends 9 ticks per bump and policy 2 one tick
    policy = MixturePolicy(alpha, epoch=5)
    actions = np.array(drive(policy, 5000, ticks_per_bump=(9, 1, 1)))
    assert np.all(actions.reshape(-1, 5) == actions.reshape(-1, 5)[:, :1])  # constant per epoch
    assert not np.any(actions == 1)  # α_i = 0 is never used
    np.testing.assert_allclose(policy.time_fractions, alpha, atol=0.01)
    assert actions[0] == 2  # the first epoch goes to the largest α
    # bumps schedule: fractions of epochs, whatever the ticks
    policy = MixturePolicy(alpha, epoch=5, schedule="bumps")
    actions = np.array(drive(policy, 5000, ticks_per_bump=(9, 1, 1)))
    assert np.all(np.abs(policy.epochs - alpha * 1000) <= 1)
    np.testing.assert_allclose(np.bincount(actions, minlength=3) / 5000, alpha, atol=1e-3)
    # random schedule: deterministic given the seed
    runs = [drive(MixturePolicy(alpha, epoch=3, schedule="random", seed=s), 600) for s in (1, 1, 2)]
    assert runs[0] == runs[1] and runs[0] != runs[2]
    assert 1 not in runs[0]
    # without ticks and bumps in info, every call is one bump and one tick
    policy = MixturePolicy([0.5, 0.5], epoch=2)
    assert [policy.act(None, {}) for _ in range(8)] == [0, 0, 1, 1, 0, 0, 1, 1]


def test_mixture_policy_rejects_bad_arguments():
    for bad in ([], [0.5, np.nan], [-0.1, 1.1], [0.0, 0.0], [0.3, 0.3]):
        with pytest.raises(ConfigError, match="alpha"):
            MixturePolicy(bad)
    for bad in (0, 2.5, True):
        with pytest.raises(ConfigError, match="epoch"):
            MixturePolicy([1.0], epoch=bad)
    with pytest.raises(ConfigError, match="schedule"):
        MixturePolicy([1.0], schedule="sobol")
    with pytest.raises(ConfigError, match="actions"):
        MixturePolicy([0.5, 0.5]).reset(fake_env())


def run_episode(env, policy, seed: int, steps: int) -> dict:
    obs, info = env.reset(seed=seed)
    policy.reset(env)
    for _ in range(steps):
        obs, _, terminated, truncated, info = env.step(policy.act(obs, info))
        assert not (terminated or truncated)
    return info


def test_simulated_coverage_of_the_mixture(lab, table1):
    """2 seeds x 2000 bounces on the cell backend (exact GCM noise) of the Table I setting, against
    the env's uniform target over the position cells: the α-mixture over positions vs each single
    policy and the uniform mixture. The bigger run is ``python -m benchmarks.coverage``."""
    env = BounceEnv(**ENV_KWARGS)
    mix = MixturePolicy.for_env(env)  # space="positions", the env's (uniform) target
    res = optimal_mixture(table1["positions"], target_vector(lab, None, "positions"))
    np.testing.assert_allclose(mix.alpha, res.alpha, atol=1e-12)
    np.testing.assert_allclose(to_grid(lab, target_vector(lab, None, "positions")),
                               env.unwrapped.task.target, atol=1e-15)
    uniform = np.full(3, 1 / 3)
    # analytic: the optimum beats every single policy and the uniform mixture (robust: it is the
    # definition of the optimum)
    assert np.all(res.residual <= res.vertex_residuals)
    assert res.residual <= res.residual_of(uniform)
    policies = {name: FixedAnglePolicy(i, phi)
                for i, (name, phi) in enumerate(zip(PHI_NAMES, PHI_DEG, strict=True))}
    policies["α-mixture"] = mix
    policies["uniform mixture"] = MixturePolicy(uniform)
    analytic = dict(zip(policies, [*np.sqrt(res.vertex_residuals), res.distance,
                                   math.sqrt(res.residual_of(uniform))], strict=True))
    seeds, steps = (0, 1), 2000
    sim = {name: [run_episode(env, p, s, steps)["distance"] for s in seeds]
           for name, p in policies.items()}
    print(f"\ncoverage distance (L2 to uniform over 183 positions), {len(seeds)} seeds x {steps} "
          f"bounces; α = {np.round(mix.alpha, 4)} (positions)")
    print(f"{'policy':>16} {'‖Aα−b‖':>8} {'simulated':>22}")
    for name, d in sim.items():
        print(f"{name:>16} {analytic[name]:>8.4f} {np.mean(d):>10.4f} "
              f"{np.array2string(np.array(d), precision=4)}")
    # the schedule realises α in time (within about one epoch's ticks)
    np.testing.assert_allclose(mix.time_fractions, mix.alpha, atol=0.03)
    # simulated: on every seed the α-mixture covers closer to uniform than any single policy and
    # than the uniform mixture (margins >= 0.01 on 12 other seeds checked by hand)
    mixed = np.array(sim["α-mixture"])
    for name in (*PHI_NAMES, "uniform mixture"):
        assert np.all(mixed < np.array(sim[name])), name

