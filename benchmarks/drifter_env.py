"""Steps per second of ``bounce_gym/Drifter-v0`` against Gymnasium's ``CartPole-v1``, measured
together.

Run with ``python -m benchmarks.drifter_env`` (``--steps``, ``--rounds``). Prints a table; asserts
nothing. Every env is built with ``gym.make`` (Gymnasium's default wrappers): ``Drifter-v0`` with
its defaults (the scb_like flow, reach task) on the ``cell`` backend (one step = one transition
of the GCM) and on the ``continuous`` backend (one step = RK4 advection of one drifter over the
default step duration in 4 substeps; it runs a tenth of the steps), and ``CartPole-v1`` as the
anchor. The runs are interleaved as in `benchmarks.env_step` — each round times every env in
turn — and the table gives the median steps/s over the rounds and the median over rounds of each
env's ratio to CartPole in the same round. The issue sets no target ratio.
"""

from __future__ import annotations

import argparse
import statistics

import bounce_gym  # noqa: F401  (registers the environments)
from benchmarks.env_step import stepper
from benchmarks.rounds import interleaved

#: (label, gym id, keyword arguments, fraction of --steps it runs)
ENVS = [
    ("Drifter-v0 cell", "bounce_gym/Drifter-v0", {"backend": "cell"}, 1.0),
    ("Drifter-v0 continuous", "bounce_gym/Drifter-v0", {"backend": "continuous"}, 0.1),
    ("CartPole-v1", "CartPole-v1", {}, 1.0),
]


def measure(n_steps: int, rounds: int) -> dict[str, list[float]]:
    """Steps/s of every env in every round, the envs interleaved within each round."""
    runs = {label: stepper(env_id, max(1, int(n_steps * share)), **kwargs)
            for label, env_id, kwargs, share in ENVS}
    return interleaved(runs, rounds)


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5_000, help="steps per env and round")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    rates = measure(args.steps, args.rounds)
    anchor = rates["CartPole-v1"]
    print(f"{'environment':<24} {'steps/s':>10} {'÷ CartPole':>11}")
    ratios = {}
    for label, *_ in ENVS:
        ratios[label] = statistics.median(r / a for r, a in zip(rates[label], anchor,
                                                                strict=True))
        print(f"{label:<24} {statistics.median(rates[label]):>10,.0f} {ratios[label]:>11.3f}",
              flush=True)
    return ratios


if __name__ == "__main__":
    main()
