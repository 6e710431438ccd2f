"""The navigation rewards against the roadmap planner (Alam, Bobadilla & Shell 2017, Alg. 1):
the progress and sparse rewards score every success of the planner above every failure of a
fixed bounce angle on the same episode; the papers' plan cost as a reward does not, which is why
it is no longer the default (docs/choices/learning_tasks.md, "The navigation reward"). Episodes run in
``BounceNavigation-v0`` on the cell backend, with its registered horizon of 200 steps."""

from __future__ import annotations

import gymnasium as gym
import pytest

import bounce_gym  # noqa: F401  (registers the ids)
from baselines.navigation import NavigationPlanner
from baselines.policy import FixedAnglePolicy

PHI = (45, 90, 135)
#: seeds of the lab on which the planner reaches the goal (a plan exists) — among them 107,
#: where a fixed 90° robot fails by bouncing in a corner for 200 one-tick steps
SEEDS = (3, 4, 9, 14, 15, 25, 27, 107)


def run(policy, seed: int, discount: float = 1.0, **task_kwargs) -> dict:
    """One episode; ``return`` is discounted by ``discount`` (the agent's γ)."""
    env = gym.make("bounce_gym/BounceNavigation-v0", backend="cell", angles=list(PHI),
                   task_kwargs={"goal_radius": 0.3, "heading_tolerance_deg": 10, **task_kwargs})
    obs, info = env.reset(seed=seed)
    policy.reset(env)
    total, weight, done = 0.0, 1.0, False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy.act(obs, info))
        total += weight * reward
        weight *= discount
        done = terminated or truncated
    return {"return": total, "success": info["is_success"], "plan_cost": info["plan_cost"]}


def fixed_policies():
    return [FixedAnglePolicy(i, d) for i, d in enumerate(PHI)]


@pytest.mark.parametrize(("task_kwargs", "discount"), [
    ({"reward": "progress"}, 1.0),                 # the default, undiscounted
    ({"reward": "progress", "gamma": 0.99}, 0.99),  # shaping and agent with the same discount
    ({"reward": "sparse"}, 1.0),
    ({"reward": "sparse", "tick_cost": 0.001}, 1.0),
], ids=repr)
def test_the_planners_successes_outscore_every_failure(task_kwargs, discount):
    compared = 0
    for seed in SEEDS:
        planner = run(NavigationPlanner(), seed, discount, **task_kwargs)
        assert planner["success"], seed
        for policy in fixed_policies():
            fixed = run(policy, seed, discount, **task_kwargs)
            if not fixed["success"]:
                assert planner["return"] > fixed["return"], (seed, policy.name)
                compared += 1
    assert compared >= 15


def test_the_plan_cost_reward_prefers_a_failure_to_a_success():
    """Seed 107: the planner's plan costs 319 (three changes of angle), so its plan-cost return
    is 100 − 319 = −219; fixed 90° never reaches the goal but only bumps in a corner, 200 steps
    of one tick: −200 scores higher."""
    planner = run(NavigationPlanner(), 107, reward="plan_cost")
    stuck = run(FixedAnglePolicy(1, 90), 107, reward="plan_cost")
    assert planner["success"] and not stuck["success"]
    assert (planner["return"], stuck["return"]) == (-219.0, -200.0)
    assert planner["plan_cost"] == 319.0


def test_the_plan_cost_info_is_the_planners_weight():
    """On arrival ``info["plan_cost"]`` is the roadmap weight of the plan the planner followed
    (w1 per tick from the start, the reset's drive included, w2 − w1 more per change)."""
    for seed in SEEDS:
        planner = NavigationPlanner()
        out = run(planner, seed)
        assert out["success"] and planner.replans == 0
        assert out["plan_cost"] == planner.predicted_weight
