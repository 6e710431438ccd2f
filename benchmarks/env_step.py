"""Steps per second of one `BounceEnv` against Gymnasium's ``CartPole-v1``, measured together.

Run with ``python -m benchmarks.env_step`` (``--steps``, ``--rounds``). Prints a table; asserts
nothing. Every env is built with ``gym.make`` (Gymnasium's default wrappers): ``Bounce-v0`` in
bounce mode on the ``kinematic``, ``pymunk`` (its exact model, ``physics="ideal"``) and ``cell``
backends, and ``CartPole-v1`` as the
anchor. The runs are interleaved — each round times ``--steps`` steps of every env in turn — so
that load on a shared machine hits all of them alike; the table gives the median steps/s over the
rounds and the median over rounds of each env's ratio to CartPole in the same round, next to the
target ratio (issue 13: ≥ 1/3 kinematic, ≥ 1/6 pymunk; the cell backend has none).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the environments)
from benchmarks.rounds import interleaved

#: (label, gym id, keyword arguments, target ratio to CartPole-v1 or None)
ENVS = [
    ("Bounce-v0 kinematic", "bounce_gym/Bounce-v0", {"backend": "kinematic"}, 1 / 3),
    ("Bounce-v0 pymunk", "bounce_gym/Bounce-v0", {"backend": "pymunk", "physics": "ideal"}, 1 / 6),
    ("Bounce-v0 cell", "bounce_gym/Bounce-v0", {"backend": "cell"}, None),
    ("CartPole-v1", "CartPole-v1", {}, None),
]


def stepper(env_id: str, n_steps: int, **kwargs) -> Callable[[], float]:
    """A callable that runs ``n_steps`` steps of a fresh env (resetting at episode ends) and
    returns the steps per second; the actions are drawn beforehand."""
    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(n_steps)]

    def run() -> float:
        start = time.perf_counter()
        for a in actions:
            _, _, terminated, truncated, _ = env.step(a)
            if terminated or truncated:
                env.reset()
        return n_steps / (time.perf_counter() - start)

    return run


def measure(n_steps: int, rounds: int) -> dict[str, list[float]]:
    """Steps/s of every env in every round, the envs interleaved within each round."""
    runs = {label: stepper(env_id, n_steps, **kwargs) for label, env_id, kwargs, _ in ENVS}
    return interleaved(runs, rounds)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5_000, help="steps per env and round")
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args(argv)
    rates = measure(args.steps, args.rounds)
    anchor = rates["CartPole-v1"]
    print(f"{'environment':<22} {'steps/s':>10} {'÷ CartPole':>11} {'target':>8}")
    for label, _, _, target in ENVS:
        ratio = statistics.median(r / a for r, a in zip(rates[label], anchor, strict=True))
        goal = f"≥ 1/{round(1 / target)}" if target else "-"
        print(f"{label:<22} {statistics.median(rates[label]):>10,.0f} {ratio:>11.3f} {goal:>8}",
              flush=True)


if __name__ == "__main__":
    main()
