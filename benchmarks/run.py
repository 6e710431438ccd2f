"""Speed of the simulator core: bounces per second per backend, world and robot count.

Run with ``make bench`` (or ``python -m benchmarks.run``). Prints a table; asserts nothing.
Each row is the best of ``--repeats`` timed runs on one process (one core).

Core rows (issue #2): one robot and 1024 independent robots on the kinematic backend, one robot
and 20 colliding robots on the pymunk backend (its exact model, ``physics="ideal"``), in
``two_rooms`` and ``grid_15x15``.
Env rows (issue #3): `BounceEnv` steps/s in bounce mode through ``gym.make`` (with Gymnasium's
default wrappers) on both backends, Gymnasium's ``CartPole-v1`` in the same run as the floor for
a Python env, and `MultiBounceEnv` with 20 robots (agent-steps/s).
Cell-model rows (issue #4): `benchmarks.scm_gcm` (SCM on ~9 M cells, GCM on 65 880 cells) and
`benchmarks.localization` (DFA construction for the 152-cell lab maps); issue #5:
`benchmarks.navigation` (all-pairs plans) and `benchmarks.coverage` (α and simulated coverage);
issue #6: `benchmarks.visibility` (partition + safe graph, random-polygon reachability);
issue #7: `benchmarks.multirobot` (steps to coverage vs m, planning time and memory for
m = 2..10, the m = 2 monitoring joint map); issue #15: `benchmarks.drifters` (the GCM of a
10^6-cell drifter layer, continuous advection against OceanParcels in the same run) and
`benchmarks.drifter_env` (``Drifter-v0`` steps/s against CartPole-v1 in the same run) and
`benchmarks.drifter_planners` (value iteration on 3 x 10^5 states, deployment counts); issue #16:
`benchmarks.patrolling` (MAECT on 188 and 1,025 vertices against Table 4.5, the Alg. 4.3 covers
against Table 4.4, ``Patrol-v0`` agent-steps/s against pistonball_v6 in the same run); issue #17:
`benchmarks.executors` (the multi-robot study and the benchmark configuration with one worker,
the local pool and Ray: wall times and the checksums of their files); issue #23:
`benchmarks.dynamic_physics` (``physics="dynamic"`` against the kinematic backend, CartPole-v1
and pistonball_v6 in the same run, median and min–max over rounds, load average); issue #24:
`benchmarks.sampled_model` (building the sampled GCM of the lab map and of a 10⁴-cell map,
against the raw kinematic simulator in the same run); issue #26: `benchmarks.jax_env` (the
functional JAX env against the native vector env at N = 1, 64 and 1,024, one XLA thread) and
`benchmarks.jax_training` (jax_ppo against SB3's PPO, env steps/s on one core each, and DQN
with hindsight relabelling, JAX and SB3, wall time to 0.90 held-out success); issue #35:
`benchmarks.bump_table` (a particle update through the tabulated bump map against the
simulator, its build time and prediction error) and `benchmarks.physics_planners` (seconds per
closed-loop planner episode on dynamic physics, against a 10,000-particle simulator update);
`benchmarks.team_vector_env` (the batched team core, ``TeamVectorEnv`` at 64 teams, against the
PettingZoo env stepped team by team in the same run, median and min–max over rounds, load
average).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from benchmarks import one_core  # noqa: F401  (before anything imports jax: one XLA thread)
from bounce_gym import worlds
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv


def _time(setup: Callable[[], Callable[[], int]], repeats: int) -> float:
    """Best rate (events per second) of ``repeats`` runs; ``setup`` returns the timed callable."""
    best = 0.0
    for _ in range(repeats):
        run = setup()
        start = time.perf_counter()
        events = run()
        best = max(best, events / (time.perf_counter() - start))
    return best


def single_robot(world, backend: str, n_bounces: int) -> Callable[[], int]:
    dyn = BounceDynamics(world, 1, backend=backend, radius=0.0, physics="ideal")
    dyn.reset(np.random.default_rng(0))
    dyn.drive_to_contact()
    angles = np.random.default_rng(1).uniform(0.2, 2 * np.pi - 0.2, n_bounces)

    def run() -> int:
        for a in angles:
            dyn.bounce(a)
        return n_bounces

    return run


def independent_robots(world, n_robots: int, n_rounds: int) -> Callable[[], int]:
    dyn = BounceDynamics(world, n_robots, backend="kinematic", robot_collisions="ignore")
    dyn.reset(np.random.default_rng(0))
    dyn.bounce_each(1.0)  # nobody is blocked yet: drive to the first contact
    angles = np.random.default_rng(1).uniform(0.2, 2 * np.pi - 0.2, (n_rounds, n_robots))

    def run() -> int:
        for row in angles:
            dyn.bounce_each(row)
        return n_rounds * n_robots

    return run


def colliding_robots(world, backend: str, n_robots: int, n_steps: int) -> Callable[[], int]:
    dyn = BounceDynamics(world, n_robots, backend=backend, radius=0.3, robot_collisions="bounce",
                         physics="ideal")
    dyn.reset(np.random.default_rng(0))
    dyn.drive_to_contact()
    angles = np.random.default_rng(1).uniform(0.2, 2 * np.pi - 0.2, (n_steps, n_robots))

    def run() -> int:
        before = int(dyn.state.bumps.sum())
        for row in angles:
            dyn.bounce(row)
        return int(dyn.state.bumps.sum()) - before  # robot-bounces, not env steps

    return run


def gym_steps(env_id: str, n_steps: int, **kwargs) -> Callable[[], int]:
    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(n_steps)]

    def run() -> int:
        for a in actions:
            _, _, terminated, truncated, _ = env.step(a)
            if terminated or truncated:
                env.reset()
        return n_steps

    return run


def multi_steps(n_robots: int, n_steps: int, **kwargs) -> Callable[[], int]:
    env = MultiBounceEnv(world="grid_15x15", n_robots=n_robots, max_cycles=10**9, **kwargs)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = [dict(zip(env.possible_agents, row.tolist(), strict=True))
               for row in rng.integers(0, 3, (n_steps, n_robots))]

    def run() -> int:
        for a in actions:
            env.step(a)
        return n_steps * n_robots

    return run


def env_rows(quick: bool) -> list[tuple[str, str, str, Callable[[], Callable[[], int]]]]:
    n = 2_000 if quick else 10_000
    return [
        ("two_rooms", "kinematic", "Bounce-v0 steps",
         lambda: gym_steps("bounce_gym/Bounce-v0", n, backend="kinematic")),
        ("two_rooms", "pymunk", "Bounce-v0 steps",
         lambda: gym_steps("bounce_gym/Bounce-v0", n, backend="pymunk", physics="ideal")),
        ("-", "gymnasium", "CartPole-v1 steps", lambda: gym_steps("CartPole-v1", n)),
        ("grid_15x15", "kinematic", "MultiBounce 20 robots",
         lambda: multi_steps(20, n // 20)),
        ("grid_15x15", "cell", "MultiBounce 5, tick",
         lambda: multi_steps(5, n // 5, backend="cell", step_mode="tick",
                             corner_rule="no_squeeze", turn_angles=[45, -45])),
    ]


def rows(quick: bool) -> list[tuple[str, str, str, Callable[[], Callable[[], int]]]]:
    scale = 0.2 if quick else 1.0
    n1 = int(20_000 * scale)
    out = []
    for name in ("two_rooms", "grid_15x15"):
        world = worlds.get(name)
        out += [
            (name, "kinematic", "1 robot", lambda w=world: single_robot(w, "kinematic", n1)),
            (name, "kinematic", "1024 independent",
             lambda w=world: independent_robots(w, 1024, int(300 * scale))),
            (name, "pymunk", "1 robot", lambda w=world: single_robot(w, "pymunk", n1 // 2)),
            (name, "pymunk", "20 colliding (r=0.3)",
             lambda w=world: colliding_robots(w, "pymunk", 20, int(1000 * scale))),
            (name, "kinematic", "20 colliding (r=0.3)",
             lambda w=world: colliding_robots(w, "kinematic", 20, int(1000 * scale))),
        ]
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer bounces per row")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(f"{'world':<12} {'backend':<10} {'robots':<22} {'robot-bounces/s':>16}")
    for world, backend, robots, setup in rows(args.quick):
        rate = _time(setup, args.repeats)
        print(f"{world:<12} {backend:<10} {robots:<22} {rate:>16,.0f}", flush=True)
    print(f"\n{'world':<12} {'backend':<10} {'environment':<22} {'(agent-)steps/s':>16}")
    for world, backend, what, setup in env_rows(args.quick):
        rate = _time(setup, args.repeats)
        print(f"{world:<12} {backend:<10} {what:<22} {rate:>16,.0f}", flush=True)
    # the cell model's analyses (issue #4)
    from benchmarks import coverage, localization, multirobot, navigation, scm_gcm, visibility

    for module in (scm_gcm, localization, navigation, visibility):
        print()
        module.main([])
    print()
    coverage.main(["--seeds", "2", "--steps", "1500"])
    print()
    multirobot.main(["--seeds", "5"])
    # throughput ratios against anchors measured in the same run (issue #13)
    from benchmarks import env_step, multirobot_scaling, planners, vector_env

    print()
    env_step.main(["--steps", "2000", "--rounds", "3"] if args.quick else [])
    print()
    vector_env.main(quick=args.quick, repeats=args.repeats)
    # the functional JAX env against the native vector env (issue #26)
    from benchmarks import jax_env

    print()
    jax_env.main(["--steps", "50", "--rounds", "3"] if args.quick else [])
    from benchmarks import jax_training

    print()
    jax_training.main(["--ppo-steps", "51200", "--sb3-steps", "4096", "--skip-dqn",
                       "--e2e-rounds", "1"] if args.quick else [])
    print()
    multirobot_scaling.main(["--steps", "4000"] if args.quick else [])
    # the batched team core against the PettingZoo env team by team
    from benchmarks import team_vector_env

    print()
    team_vector_env.main(["--steps", "200", "--rounds", "3"] if args.quick else [])
    # the pymunk backend's dynamic physics (issue #23)
    from benchmarks import dynamic_physics

    print()
    dynamic_physics.main(["--steps", "2000", "--agent-steps", "2000", "--rounds", "3"]
                         if args.quick else [])
    from benchmarks import sampled_model

    print()
    sampled_model.main(["--quick"] if args.quick else [])
    # the tabulated bump map and the closed-loop planners on dynamic physics (issue #35)
    from benchmarks import bump_table, physics_planners

    print()
    bump_table.main(["--maps", "lab_localization_a"] if args.quick else [])
    print()
    physics_planners.main(["--episodes", "2"] if args.quick else [])
    print()
    planners.main(quick=args.quick, repeats=args.repeats)
    # drifters (issue #15): GCM of a 10^6-cell layer, advection vs Parcels, Drifter-v0 steps/s
    from benchmarks import drifter_env, drifters

    print()
    drifters.main((["--quick"] if args.quick else []) + ["--repeats", str(args.repeats)])
    print()
    drifter_env.main(["--steps", "2000", "--rounds", "3"] if args.quick else [])

    # drifter planners: value iteration on 3 x 10^5 states, deployment counts
    from benchmarks import drifter_planners

    print()
    drifter_planners.main((["--quick"] if args.quick else []) + ["--repeats", str(args.repeats)])

    # stochastic patrolling (issue #16): MAECT, Alg. 4.3 covers, Patrol-v0 agent-steps/s
    from benchmarks import patrolling

    print()
    patrolling.main((["--quick"] if args.quick else []) + ["--repeats", str(args.repeats)])

    # evaluation sweeps (issue #17): one worker, the local pool, Ray (skipped without ray)
    from benchmarks import executors

    print()
    executors.main(["--quick"] if args.quick else [])


if __name__ == "__main__":
    main()
