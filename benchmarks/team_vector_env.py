"""Throughput of the batched team core (`TeamVectorEnv`) against the PettingZoo env, in one run.

Run with ``python -m benchmarks.team_vector_env`` (``--steps``, ``--teams``, ``--rounds``).
Prints a table; asserts nothing. The row, on configs/benchmark.yaml's cell-backend monitoring
configuration (``MultiBounceMonitoring-v0``: grid_15x15, 2 robots, tick mode, angles 45°, 90°,
135°, corner rule no_squeeze, collisions ignored, the two half regions; 500-step episodes, so
resets included):

* agent-steps/s of `TeamVectorEnv` at B = 64 teams ÷ B = 64 `MultiBounceEnv` stepped team by team
  (the anchor: each step a dict of actions per team, each team reset when its episode ends);
  target ≥ 10. One agent-step is one robot's share of a parallel step.

Random actions are drawn beforehand. The envs are built once and interleaved: each round times
both in turn, so the load of a shared machine hits them alike; the ratio is taken within a
round, and the table gives its median and min–max over the rounds, with the one-minute load
average before and after.
"""

from __future__ import annotations

import argparse
import os
import statistics
from collections.abc import Callable

import numpy as np

from benchmarks.dynamic_physics import timed
from benchmarks.rounds import interleaved, ratio, spread, verdict
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.envs.team_vector_env import TeamVectorEnv

#: configs/benchmark.yaml's ``multirobot-monitoring-15x15`` env_kwargs
MONITORING = {"world": "grid_15x15", "task": "monitoring", "n_robots": 2, "backend": "cell",
              "step_mode": "tick", "angles": [45, 90, 135], "corner_rule": "no_squeeze",
              "robot_collisions": "ignore",
              "task_kwargs": {"regions": [[[0, 0], [7.5, 0], [7.5, 15], [0, 15]],
                                          [[7.5, 0], [15, 0], [15, 15], [7.5, 15]]]}}
BATCHED, ANCHOR = "TeamVectorEnv", "MultiBounceEnv team by team"
TARGET = 10.0


def batched(teams: int, steps: int) -> Callable[[], int]:
    """`TeamVectorEnv` of ``teams`` teams, reset; runs ``steps`` steps, returns agent-steps."""
    env = TeamVectorEnv(teams, **MONITORING)
    env.reset(seed=0)
    m = env.n_robots
    actions = np.random.default_rng(1).integers(0, 3, (steps, teams, m))

    def run() -> int:
        for row in actions:
            env.step(row)
        return steps * teams * m

    return run


def team_by_team(teams: int, steps: int) -> Callable[[], int]:
    """``teams`` `MultiBounceEnv`, reset with seeds 0, 1, …; runs ``steps`` steps of each in
    turn (a team whose episode ended is reset first), returns agent-steps."""
    envs = [MultiBounceEnv(**MONITORING) for _ in range(teams)]
    for i, env in enumerate(envs):
        env.reset(seed=i)
    agents = envs[0].possible_agents
    actions = [[dict(zip(agents, row.tolist(), strict=True)) for row in step]
               for step in np.random.default_rng(1).integers(0, 3, (steps, teams, len(agents)))]

    def run() -> int:
        for step in actions:
            for env, action in zip(envs, step, strict=True):
                if not env.agents:
                    env.reset()
                env.step(action)
        return steps * teams * len(agents)

    return run


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000,
                        help="steps of the batched env per round (the anchor runs a tenth)")
    parser.add_argument("--teams", type=int, default=64)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    runs = {BATCHED: timed(batched(args.teams, args.steps)),
            ANCHOR: timed(team_by_team(args.teams, max(args.steps // 10, 1)))}
    load_before = os.getloadavg()[0]
    rates = interleaved(runs, args.rounds)
    load_after = os.getloadavg()[0]
    print(f"Batched team core, monitoring 15x15, 2 robots, B = {args.teams}: {args.rounds} "
          f"rounds, interleaved; load average {load_before:.1f} before, {load_after:.1f} after, "
          f"{os.cpu_count()} cores")
    print(f"{'environment':<30} {'agent-steps/s':>14} {'min–max':>20}")
    for label, values in rates.items():
        print(f"{label:<30} {statistics.median(values):>14,.0f} {spread(values, ',.0f'):>20}")
    per_round = [a / b for a, b in zip(rates[BATCHED], rates[ANCHOR], strict=True)]
    row = ratio(per_round, TARGET)
    name = f"{BATCHED} ÷ {ANCHOR}"
    print(f"{'ratio (within a round)':<50} {'median':>7} {'min–max':>15} {'target':>8}")
    print(f"{name:<50} {row['median']:>7.1f} {spread(per_round, '.1f'):>15} "
          f"{'≥ ' + format(TARGET, 'g'):>8}{verdict(row)}", flush=True)
    return dict(rates=rates, ratio=row, load=(load_before, load_after))


if __name__ == "__main__":
    main()
