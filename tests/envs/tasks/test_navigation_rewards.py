"""The navigation task's ``reward`` options: the papers' plan cost in every step's info, the
sparse success reward, and the progress reward — potential-based shaping that telescopes."""

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import bounce_gym  # noqa: F401  (registers the ids)
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.errors import ConfigError

NAV = "bounce_gym/BounceNavigation-v0"
#: a goal region that random angles reach now and then (any heading within 90°)
EASY = {"goal_radius": 1.5, "heading_tolerance_deg": 90}
REWARDS = [{"reward": "progress"}, {"reward": "progress", "gamma": 0.9},
           {"reward": "sparse"}, {"reward": "sparse", "tick_cost": 0.01},
           {"reward": "plan_cost"}]


def lockstep(kwargs_a, kwargs_b, seed, backend="cell", steps=400):
    """Run two navigation envs that differ only in their task options on the same seed and
    actions; yields (info before, step of a, step of b) per step, through resets."""
    a = gym.make(NAV, backend=backend, task_kwargs={**EASY, **kwargs_a})
    b = gym.make(NAV, backend=backend, task_kwargs={**EASY, **kwargs_b})
    rng = np.random.default_rng(seed)
    _, info_a = a.reset(seed=seed)
    _, info_b = b.reset(seed=seed)
    for _ in range(steps):
        action = int(rng.integers(3))
        out_a, out_b = a.step(action), b.step(action)
        np.testing.assert_array_equal(out_a[0], out_b[0])  # the reward changes nothing else
        yield info_a, info_b, out_a, out_b, a.unwrapped.task
        info_a, info_b = out_a[4], out_b[4]
        if out_a[2] or out_a[3]:
            _, info_a = a.reset()
            _, info_b = b.reset()


def potential_after(task, info) -> float:
    return 0.0 if info["is_success"] else task.potential(info["position"])


@pytest.mark.parametrize("backend", ["cell", "kinematic"])
def test_progress_minus_sparse_telescopes_with_gamma_one(backend):
    """With γ = 1 every step's progress reward is the sparse one plus Φ(s') − Φ(s), so an
    episode's progress return is its sparse return plus Φ(s_T) − Φ(s_0), Φ = 0 at the goal."""
    episodes, successes = 0, 0
    gap, first = 0.0, None
    for info_p, _, (_, r_p, term, trunc, info), (_, r_s, *_), task in lockstep(
            {"reward": "progress", "gamma": 1.0}, {"reward": "sparse"}, seed=3, backend=backend):
        if first is None:
            first = task.potential(info_p["position"])
        gap += r_p - r_s
        if term or trunc:
            assert gap == pytest.approx(potential_after(task, info) - first, abs=1e-12)
            episodes += 1
            successes += term
            gap, first = 0.0, None
    assert episodes >= 3 and successes >= 1


def test_each_progress_step_adds_the_potential_difference():
    gamma = 0.9
    steps = 0
    for info_p, _, (_, r_p, *_, info), (_, r_s, *_), task in lockstep(
            {"reward": "progress", "gamma": gamma}, {"reward": "sparse"}, seed=5):
        shaping = gamma * potential_after(task, info) - task.potential(info_p["position"])
        assert r_p - r_s == pytest.approx(shaping, abs=1e-12)
        steps += 1
    assert steps == 400


def test_discounted_progress_differs_by_discounted_potentials():
    """Σ γ^t (r_progress − r_sparse) = γ^T Φ(s_T) − Φ(s_0) with the task's γ."""
    gamma = 0.9
    total, discount, first, checked = 0.0, 1.0, None, 0
    for info_p, _, (_, r_p, term, trunc, info), (_, r_s, *_), task in lockstep(
            {"reward": "progress", "gamma": gamma}, {"reward": "sparse"}, seed=8):
        if first is None:
            first = task.potential(info_p["position"])
        total += discount * (r_p - r_s)
        discount *= gamma
        if term or trunc:
            assert total == pytest.approx(discount * potential_after(task, info) - first,
                                          abs=1e-12)
            total, discount, first, checked = 0.0, 1.0, None, checked + 1
    assert checked >= 3


def test_sparse_rewards_the_goal_and_charges_ticks():
    for _, _, (_, reward, term, _, info), _, _ in lockstep(
            {"reward": "sparse", "tick_cost": 0.01}, {"reward": "plan_cost"}, seed=2):
        ticks = info["step_ticks"] if not term else None
        if term:
            assert 1.0 - 0.01 * info["step_ticks"] <= reward < 1.0
        else:
            assert reward == -0.01 * ticks


def test_plan_cost_is_reported_whatever_the_reward():
    """info["plan_cost"] = w1 × ticks since the episode start (ticks to the goal on arrival)
    + (w2 − w1) × angle changes, the same under every reward."""
    changes = 0
    for info_a, _, (_, _, term, trunc, info), (*_, info_b), _ in lockstep(
            {"reward": "progress"}, {"reward": "sparse", "tick_cost": 0.5}, seed=4):
        assert info_a["plan_cost"] == info_a["ticks"] + 99.0 * changes  # after reset: the drive
        changes += info["angle_changed"]
        ticks = info["ticks_to_goal"] if term else info["ticks"]
        assert info["plan_cost"] == info_b["plan_cost"] == ticks + 99.0 * changes
        if term or trunc:
            changes = 0


def test_the_potential_is_minus_the_normalised_geodesic_distance():
    """On the 10 × 10 square (cell backend) the geodesic distance along king moves between cell
    centres is the octile distance; Φ divides it by the largest one from the goal."""
    env = BounceEnv(world="square", backend="cell", task="navigation",
                    task_kwargs={"goal": {"position": [2.5, 1.5], "heading": 0.0}})
    env.reset(seed=0)
    task = env.task
    assert task.potential([2.5, 1.5]) == 0.0
    assert task.potential([2.9, 1.1]) == 0.0  # the same cell

    def octile(col, row):
        dx, dy = abs(col - 2), abs(row - 1)
        return max(dx, dy) + (math.sqrt(2) - 1) * min(dx, dy)

    far = octile(9, 9)
    for col, row in [(9, 9), (0, 0), (5, 1), (7, 4)]:
        assert task.potential([col + 0.5, row + 0.5]) == pytest.approx(-octile(col, row) / far)


def test_reaching_the_goal_ends_the_shaping_at_zero():
    """A tick-mode robot driving East into the goal: every step earns γΦ(s') − Φ(s), the last
    one 1 + 0 − Φ(s)."""
    env = BounceEnv(world="square", backend="cell", task="navigation", step_mode="tick",
                    task_kwargs={"reward": "progress", "gamma": 1.0, "goal_radius": 0.3})
    env.reset(seed=0, options={"start": {"position": [1.5, 5.5], "heading": 0.0},
                               "goal": {"position": [6.5, 5.5], "heading": 0.0}})
    rewards = [env.step(0)[1] for _ in range(5)]
    # Φ = −(5 − k)/far after k steps; far: the octile distance from the goal's cell (6, 5) to
    # the farthest cells, (0, 0) and (0, 9) as (col, row)
    far = 6 + (math.sqrt(2) - 1) * 5
    assert rewards[:4] == pytest.approx([1 / far] * 4)
    assert rewards[4] == pytest.approx(1.0 + 1 / far)
    assert env.task.reached


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"reward": "dense"}, "reward"),
    ({"reward": 3}, "reward"),
    ({"reward": "plan_cost", "tick_cost": 1.0}, "tick_cost"),
    ({"reward": "sparse", "gamma": 0.99}, "gamma"),
    ({"reward": "plan_cost", "gamma": 1.0}, "gamma"),
    ({"gamma": 0.0}, "gamma"),
    ({"gamma": 1.01}, "gamma"),
    ({"gamma": True}, "gamma"),
    ({"tick_cost": -0.1}, "tick_cost"),
    ({"goal_bonus": "1"}, "goal_bonus"),
])
def test_bad_reward_options_raise_config_error_naming_the_field(kwargs, field):
    with pytest.raises(ConfigError, match=rf"^{field}: "):
        BounceEnv(world="lab_navigation", task="navigation", task_kwargs=kwargs)


def test_defaults():
    task = gym.make(NAV).unwrapped.task
    assert (task.reward, task.goal_bonus, task.tick_cost, task.gamma) == ("progress", 1.0, 0.0,
                                                                         1.0)
    papers = BounceEnv(world="lab_navigation", task="navigation",
                       task_kwargs={"reward": "plan_cost"}).task
    assert (papers.goal_bonus, papers.w1, papers.w2) == (100.0, 1.0, 100.0)


@pytest.mark.parametrize("backend", ["kinematic", "pymunk", "cell"])
@pytest.mark.parametrize("kwargs", REWARDS, ids=repr)
def test_gymnasium_check_env_with_every_reward(kwargs, backend):
    env = gym.make(NAV, backend=backend, task_kwargs=kwargs)
    check_env(env.unwrapped, skip_render_check=True)


def test_goal_potentials_are_kept_per_goal_node_and_equal_a_fresh_computation():
    env = BounceEnv(task="navigation", backend="cell", angles=[45, 90, 135])
    task = env.core.task
    geodesic = task.geodesic
    for node in (0, geodesic.n_nodes - 1, 0):
        phi = task.goal_potentials(node)
        distance = geodesic.distances_to_node(node)
        finite = np.isfinite(distance)
        expect = np.where(finite, -distance / distance[finite].max(), -1.0)
        assert np.array_equal(phi, expect) and not phi.flags.writeable
    assert task.goal_potentials(0) is task.goal_potentials(0)  # a lookup the second time
    env.reset(seed=3)
    goal = int(geodesic.node_of(task.goal[0][0])[0])
    assert task.potentials is task.goal_potentials(goal)
