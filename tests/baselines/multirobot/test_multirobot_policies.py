"""Algorithm 1 and Algorithm 2 executed in `MultiBounceEnv` (Alam & Bobadilla 2020, §4.1-4.2;
docs/choices/multirobot.md, "A neighbour jump is a timed turn").

On the ``cell`` backend the env must follow the plans exactly: the joint cell after every step is
the plan's, neighbour jumps are turn commands, coverage completes at the predicted step, and a
monitoring cycle repeats with no shared cell and no robot contact.
"""

import math

import numpy as np
import pytest

from baselines.multirobot import CoverageResult
from baselines.multirobot.monitoring import joint_monitoring_cycles
from baselines.multirobot.policies import (
    CoveragePlanPolicy,
    MonitoringPlanPolicy,
    cycle_start,
    regions_of,
)
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.errors import ConfigError

COVER = dict(world="grid_10x10", task="coverage", backend="cell", step_mode="tick",
             angles=[45, 90, 135], turn_angles=[45, -45], corner_rule="no_squeeze",
             max_cycles=5000)
MONITOR = dict(world="grid_10x10", n_robots=2, task="monitoring", backend="cell",
               step_mode="tick", angles=[45, 90, 135], corner_rule="no_squeeze",
               robot_collisions="ignore", max_cycles=300)


def _run(env, policy, seed, plan_only=False):
    """Reset and run to the episode's end (or the end of the coverage plan)."""
    obs, infos = env.reset(seed=seed, options=policy.start_options(env, seed))
    policy.reset(env)
    steps = policy.executable_steps if plan_only else env.max_cycles
    model = env.cell_model()
    state = env.core.state
    cells, coverage = [model.cell_of(state.position, state.heading)], []
    while env.agents and len(coverage) < steps:
        obs, _, _, _, infos = env.step(policy.act(obs, infos))
        cells.append(model.cell_of(state.position, state.heading))
        coverage.append(infos["robot_0"].get("coverage"))
    return np.array(cells), coverage, infos


@pytest.mark.parametrize("m, seed", [(2, 0), (2, 2), (3, 1), (5, 0)])
def test_coverage_plan_is_executed_exactly(m, seed):
    env = MultiBounceEnv(n_robots=m, **COVER)
    policy = CoveragePlanPolicy.for_env(env)
    cells, coverage, _ = _run(env, policy, seed, plan_only=True)
    plan = np.array(policy.result.trajectory)
    assert policy.executable_steps == len(plan) - 1
    assert np.array_equal(cells, plan)
    full = next(t for t, c in enumerate(coverage, start=1) if c >= 1.0)
    assert full == policy.predicted_steps_to_full == policy.result.steps_to_full
    if m == 2 and seed in (0, 2):
        assert policy.result.jumps  # these seeds need neighbour jumps: turn commands ran


def test_coverage_plan_with_a_minimum_separation_is_executed_exactly():
    env = MultiBounceEnv(n_robots=3, min_sep_cells=1, **COVER)
    policy = CoveragePlanPolicy.for_env(env)
    assert policy.joint_model.min_sep_cells == 1
    cells, coverage, _ = _run(env, policy, 0, plan_only=True)
    assert np.array_equal(cells, np.array(policy.result.trajectory))
    assert coverage[-1] == 1.0 and len(coverage) == policy.predicted_steps_to_full


def test_one_angle_per_robot():
    env = MultiBounceEnv(n_robots=3, **COVER)
    policy = CoveragePlanPolicy.for_env(env, phi=[45, 135, 90])
    assert policy.joint_model.angles == [45.0, 135.0, 90.0] and policy.phi_index == [0, 2, 1]
    cells, coverage, _ = _run(env, policy, 2, plan_only=True)
    assert np.array_equal(cells, np.array(policy.result.trajectory))
    with pytest.raises(ConfigError, match="one per robot"):
        CoveragePlanPolicy.for_env(env, phi=[45, 135])


def test_jumps_are_one_turn_command_and_the_rest_wait():
    env = MultiBounceEnv(n_robots=2, **COVER)
    policy = CoveragePlanPolicy.for_env(env)
    env.reset(seed=0)
    policy.reset(env)
    t = policy.result.jumps[0]
    row = policy.actions[t]
    turned = [i for i in range(2) if row[i] >= 3]
    assert len(turned) == 1 and policy.actions[t - 1] == [2, 2]  # φ = 135° is index 2


def test_plan_stops_at_an_edge_no_command_can_execute():
    env = MultiBounceEnv(n_robots=2, **COVER)
    policy = CoveragePlanPolicy.for_env(env)
    env.reset(seed=0)
    policy.reset(env)
    res = policy.result
    t = res.jumps[0]
    kinds = list(res.edge_kinds)
    kinds[t] = "random"
    broken = CoverageResult(res.trajectory, kinds, res.coverage, res.coverage_all,
                            res.steps_to_full, res.checkpoint_length, res.collisions,
                            res.collisions_to_full, res.visits, res.n_reachable, res.n_free)
    assert len(policy._compile(broken, env)) == t


@pytest.mark.parametrize("kwargs, message", [
    (dict(turn_angles=[90, -90]), "need turn commands of ±45°"),
    (dict(turn_angles=[]), "need turn commands of ±45°"),
    (dict(angles=[45, 90]), "135° is not among robot_0's angles"),
    (dict(step_mode="bounce"), "step_mode='tick'"),
])
def test_coverage_planner_rejects_envs_it_cannot_drive(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        CoveragePlanPolicy.for_env(MultiBounceEnv(n_robots=2, **{**COVER, **kwargs}))


def test_coverage_plan_on_a_continuous_backend_starts_on_its_cells():
    env = MultiBounceEnv(n_robots=3, **{**COVER, "backend": "kinematic", "robot_radius": 0.3,
                                        "max_cycles": 200})
    policy = CoveragePlanPolicy.for_env(env)
    env.reset(seed=4, options=policy.start_options(env, 4))
    policy.reset(env)
    model = policy.joint_model.model
    assert np.array_equal(model.cell_of(env.core.state.position, env.core.state.heading),
                          policy.result.trajectory[0])
    _, coverage, _ = _run(env, policy, 4)
    assert 0 < coverage[0] <= coverage[-1] <= 1


@pytest.mark.parametrize("phi", [45, 90])
def test_monitoring_cycle_replays_collision_free_and_visits_regions(phi):
    env = MultiBounceEnv(**MONITOR)
    policy = MonitoringPlanPolicy.for_env(env, phi=phi, start="cycle")
    assert policy.r > 0
    model = env.cell_model()
    regions = regions_of(env, model)
    for seed in range(3):
        cells, _, infos = _run(env, policy, seed)
        pos = cells % model.n_positions
        assert not np.any(pos[:, 0] == pos[:, 1])
        period = policy.period
        assert np.array_equal(cells[period], cells[0])
        for i in range(2):  # every period, robot i passes through its own region
            for start in range(0, len(cells) - period, period):
                assert np.isin(pos[start:start + period, i], regions[i]).any()
        assert cells[0].tolist() == [int(z) for z in policy.result.split(policy.start_cell)]


def test_monitoring_prediction_is_the_time_measured_on_the_cycle():
    """On the cell backend the robots run the cycle exactly: over whole periods the task's
    ``in_region_fraction`` is the planner's ``predicted_in_region``."""
    env = MultiBounceEnv(**MONITOR)
    policy = MonitoringPlanPolicy.for_env(env, phi=90, start="cycle")
    for seed in range(3):
        obs, infos = env.reset(seed=seed, options=policy.start_options(env, seed))
        policy.reset(env)
        measured = []
        for _ in range(2 * policy.period):
            obs, _, _, _, infos = env.step(policy.act(obs, infos))
            measured.append(np.mean(infos["robot_0"]["in_region_fraction"]))
        assert 0.0 < policy.predicted_in_region < 1.0
        assert np.mean(measured) == pytest.approx(policy.predicted_in_region, abs=1e-9)


def test_monitoring_contacts_are_zero_on_the_cycle_and_groups_match_algorithm_2():
    env = MultiBounceEnv(**{**MONITOR, "robot_collisions": "bounce"})
    policy = MonitoringPlanPolicy.for_env(env, phi=90, start="cycle")
    model = env.cell_model()
    direct = joint_monitoring_cycles(model, [math.radians(90)] * 2, regions_of(env, model),
                                 forbid_swaps=True)
    assert policy.r == direct.r > 0
    obs, infos = env.reset(seed=1, options=policy.start_options(env, 1))
    policy.reset(env)
    contacts = 0
    while env.agents:
        obs, _, _, _, infos = env.step(policy.act(obs, infos))
        contacts += infos["robot_0"]["robot_contacts"]
    assert contacts == 0


def test_monitoring_cycles_with_a_safety_margin_keep_it():
    env = MultiBounceEnv(**MONITOR)
    policy = MonitoringPlanPolicy.for_env(env, phi=90, min_sep_cells=1, start="cycle")
    assert 0 < policy.r < MonitoringPlanPolicy.for_env(env, phi=90).r
    rc = env.cell_model().position_rc
    for seed in range(3):
        cells, _, _ = _run(env, policy, seed)
        pos = rc[cells % env.cell_model().n_positions]
        assert np.abs(pos[:, 0] - pos[:, 1]).max(axis=1).min() > 1


def test_monitoring_without_groups_falls_back_to_the_env_start():
    env = MultiBounceEnv(**{**MONITOR, "robot_collisions": "bounce"})
    policy = MonitoringPlanPolicy.for_env(env, phi=45, start="cycle")  # swaps forbidden: no group
    assert policy.r == 0 and policy.start_options(env, 0) is None
    env.reset(seed=0)
    policy.reset(env)
    assert policy.act({"robot_0": None, "robot_1": None}, {}) == {"robot_0": 0, "robot_1": 0}


def test_monitoring_start_is_the_env_draw_unless_the_cycle_is_asked_for():
    env = MultiBounceEnv(**MONITOR)
    drawn = MonitoringPlanPolicy.for_env(env, phi=90)
    cycle = MonitoringPlanPolicy(drawn.result, drawn.phi_index, start="cycle")
    assert (drawn.start, drawn.name) == ("draw", "planner")
    assert cycle.name == "planner (cycle start)"
    for seed in (0, 7, 1234):
        assert drawn.start_options(env, seed) is None
        assert drawn.group is drawn.predicted_in_region is None
        group, cell = cycle_start(drawn.result, seed)
        options = cycle.start_options(env, seed)
        assert (cycle.group, cycle.start_cell) == (group, cell)
        assert group == seed % drawn.r and cell in drawn.result.cycles[group]
        assert options == drawn.cycle_options(seed) == drawn.result.start_options(cell)
    with pytest.raises(ConfigError, match="start: expected one of"):
        MonitoringPlanPolicy(drawn.result, drawn.phi_index, start="fixed")


def test_monitoring_planner_needs_two_robots_and_the_monitoring_task():
    with pytest.raises(ConfigError, match="2 robots"):
        MonitoringPlanPolicy.for_env(MultiBounceEnv(**{**MONITOR, "n_robots": 3}))
    with pytest.raises(ConfigError, match="task must be 'monitoring'"):
        MonitoringPlanPolicy.for_env(MultiBounceEnv(**{**MONITOR, "task": "coverage"}))
