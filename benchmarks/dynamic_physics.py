"""Throughput of the pymunk backend's ``physics="dynamic"`` against anchors measured with it.

Run with ``python -m benchmarks.dynamic_physics`` (``--steps``, ``--agent-steps``, ``--rounds``).
Prints a table; asserts nothing. Issue 23's rows:

* ``Bounce-v0`` with ``backend="pymunk", physics="dynamic"`` steps/s ÷ the same env on the
  ``kinematic`` backend (target ≥ 1/4, issue 39; issue 23's was 1/10), and ÷ Gymnasium's
  ``CartPole-v1`` (reported). Every env
  is built with ``gym.make`` (Gymnasium's default wrappers), bounce mode, its defaults otherwise,
  actions drawn beforehand (`benchmarks.env_step.stepper`).
* `MultiBounceEnv` with 20 robots under dynamic physics (``grid_15x15``, robot radius 0.3,
  ``robot_collisions="bounce"``, bounce mode, random discrete actions: the m = 20 env of
  `benchmarks.multirobot_scaling`) agent-steps/s ÷ PettingZoo's
  ``pistonball_v6`` (20 pistons, itself a pymunk env; random actions, no rendering) agent-steps/s
  (target ≥ 1). One agent-step is one agent's share of a parallel step. pistonball needs only
  pygame and pymunk, both dependencies of bounce_gym; without ``pettingzoo.butterfly`` the row
  says it is skipped.

The envs are built once and interleaved: each round times every env in turn, so that the load
of a shared machine hits all of them alike. Each ratio is taken within a round; the table gives
its median and spread (min–max) over the rounds, next to the median rates, and the one-minute
load average before and after the measurement.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

import bounce_gym  # noqa: F401  (registers the environments)
from benchmarks.env_step import stepper
from benchmarks.multirobot_scaling import multi_env, pistonball
from benchmarks.rounds import interleaved, ratio, spread, verdict

#: (label, gym id, keyword arguments) of the single-robot envs
SINGLE = [
    ("Bounce-v0 dynamic", "bounce_gym/Bounce-v0", {"backend": "pymunk", "physics": "dynamic"}),
    ("Bounce-v0 kinematic", "bounce_gym/Bounce-v0", {"backend": "kinematic"}),
    ("CartPole-v1", "CartPole-v1", {}),
]
MULTI, PISTONBALL = "MultiBounce 20 dynamic", "pistonball_v6 20 pistons"
N_ROBOTS = 20
#: (numerator, denominator, target ratio or None)
RATIOS = [
    ("Bounce-v0 dynamic", "Bounce-v0 kinematic", 1 / 4),
    ("Bounce-v0 dynamic", "CartPole-v1", None),
    (MULTI, PISTONBALL, 1.0),
]


def timed(run: Callable[[], int]) -> Callable[[], float]:
    """A function that calls ``run`` (which returns the agent-steps it ran) and returns the
    agent-steps per second."""
    def rate() -> float:
        start = time.perf_counter()
        n = run()
        return n / (time.perf_counter() - start)

    return rate


def measure(steps: int, agent_steps: int, rounds: int) -> dict[str, list[float]]:
    """(Agent-)steps/s of every env in every round, the envs interleaved within each round."""
    runs = {label: stepper(env_id, steps, **kwargs) for label, env_id, kwargs in SINGLE}
    env_steps = max(agent_steps // N_ROBOTS, 1)
    runs[MULTI] = timed(multi_env(N_ROBOTS, "pymunk", env_steps, physics="dynamic"))
    piston = pistonball(env_steps)
    if piston is not None:
        runs[PISTONBALL] = timed(piston)
    return interleaved(runs, rounds)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3_000,
                        help="steps of each single-robot env per round")
    parser.add_argument("--agent-steps", type=int, default=3_000,
                        help="agent-steps of each 20-agent env per round")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    load_before = os.getloadavg()[0]
    rates = measure(args.steps, args.agent_steps, args.rounds)
    load_after = os.getloadavg()[0]
    print(f"Dynamic physics (issues 23, 39): {args.rounds} rounds, interleaved; load average "
          f"{load_before:.1f} before, {load_after:.1f} after, {os.cpu_count()} cores")
    print(f"{'environment':<26} {'(agent-)steps/s':>16} {'min–max':>16}")
    for label, values in rates.items():
        print(f"{label:<26} {statistics.median(values):>16,.0f} {spread(values, ',.0f'):>16}")
    print(f"{'ratio (within a round)':<50} {'median':>7} {'min–max':>13} {'target':>8}")
    ratios = {}
    for num, den, target in RATIOS:
        name = f"{num} ÷ {den}"
        if den not in rates:
            print(f"{name:<50} skipped: pettingzoo.butterfly does not import")
            continue
        per_round = [a / b for a, b in zip(rates[num], rates[den], strict=True)]
        row = ratios[name] = ratio(per_round, target)
        goal = "-" if target is None else (f"≥ {target:g}" if target >= 1
                                           else f"≥ 1/{round(1 / target)}")
        print(f"{name:<50} {row['median']:>7.3f} {spread(per_round, '.3f'):>13} {goal:>8}"
              f"{verdict(row)}", flush=True)
    return dict(rates=rates, ratios=ratios, load=(load_before, load_after))


if __name__ == "__main__":
    main()
