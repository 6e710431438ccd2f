"""Settings of the particle localization filter, compared on the tuning seeds (issue 34).

Run with ``python -m benchmarks.particle_tuning``. Each setting runs the localization env on
lab_localization_a (kinematic backend unless ``--physics dynamic``, Φ = {45°, 135°}, horizon
200 steps) with the task's filter "particles" and `ParticleLocalizationPolicy.for_env(env)`
acting, one episode per seed, and prints the share of correct and of wrong claims with their
Wilson intervals and the time per episode. A setting changes the `ParticleBelief` arguments of
both the task's belief and the policy's (roughening ``jitter_deg``, clock ``tolerance`` and
``slack``, augmented MCL's ``alpha_slow``, ``alpha_fast`` and ``inject_below``) and the task's
claim rule (``claim_ess``, ``claim_bumps``, ``claim_replicas``); the others keep the defaults of
`bounce_gym.dynamics.particles` and `bounce_gym.envs.tasks.localization`. ``--particles`` sets
the particle count of both.

The seeds are the first ``--n`` of `baselines.seeds.TUNING_SEEDS`, so the figures that choose
the defaults never come from an evaluation episode. ``--seeds evaluation`` measures the
chosen defaults on the first ``--n`` evaluation seeds instead (the rows of
docs/localization_belief.md); it refuses every setting but ``default``.
"""

from __future__ import annotations

import argparse
import math
import time
from contextlib import ExitStack
from typing import TextIO
from unittest import mock

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.localization import ParticleLocalizationPolicy
from baselines.seeds import EVALUATION_SEEDS, TUNING_SEEDS
from bounce_gym.dynamics.particles import DEFAULT_PARTICLES, ParticleBelief
from bounce_gym_experiments.runner import run_episode
from bounce_gym_experiments.stats import rate

#: setting name -> (ParticleBelief keyword arguments, task keyword arguments)
SETTINGS = {
    "default": ({}, {}),
    "no-roughening": ({"jitter_deg": 0.0}, {}),
    "roughening-1deg": ({"jitter_deg": 1.0}, {}),
    "exact-clocks": ({"tolerance": 0}, {}),
    "no-injection": ({"alpha_fast": 0.05, "alpha_slow": 0.05}, {}),
    "table-8.3": ({"inject_below": 1.0}, {}),
    "fast-0.5": ({"alpha_fast": 0.5}, {}),
    "no-ess-floor": ({}, {"claim_ess": 0.0}),
    "ess-0.3": ({}, {"claim_ess": 0.3}),
    "one-bump": ({}, {"claim_bumps": 1}),
    "three-bumps": ({}, {"claim_bumps": 3}),
    "five-bumps": ({}, {"claim_bumps": 5}),
    "eight-bumps": ({}, {"claim_bumps": 8}),
    "no-replica": ({}, {"claim_replicas": 0}),
    "two-replicas": ({}, {"claim_replicas": 2}),
    "mass-only": ({"alpha_fast": 0.05}, {"claim_ess": 0.0, "claim_bumps": 1,
                                          "claim_replicas": 0}),
}

#: the modules that build a ParticleBelief for the task and for the policy
_BUILDERS = ("bounce_gym.envs.tasks.localization", "baselines.localization.particle_policy")

NOISE = {"type": "reliable", "r": 0.9, "eps_deg": 5}
HORIZON = 200


def _belief_class(options: dict) -> type[ParticleBelief]:
    """`ParticleBelief` with ``options`` (``jitter_deg`` in degrees) in place of its defaults."""
    fixed = dict(options)
    if "jitter_deg" in fixed:
        fixed["jitter"] = math.radians(fixed.pop("jitter_deg"))

    class Tuned(ParticleBelief):
        def __init__(self, model, dynamics, n_particles=DEFAULT_PARTICLES, **kwargs) -> None:
            super().__init__(model, dynamics, n_particles, **{**kwargs, **fixed})

    return Tuned


def measure(setting: str, seeds: range, noise: bool, log: TextIO | None = None,
            particles: int = DEFAULT_PARTICLES, physics: str | None = None) -> dict:
    """Correct and wrong-claim rates (with Wilson intervals) and seconds per episode; with
    ``log``, one CSV line per episode (setting, seed, correct, wrong_claim, claims, steps,
    seconds) as it ends."""
    options, task = SETTINGS[setting]
    kwargs = {"backend": "kinematic", "angles": [45, 135],
              "task_kwargs": {"filter_factory": "particles", "particles": particles,
                              "claim_threshold": 0.99, **task}}
    if physics is not None:
        kwargs.update(backend="pymunk", physics=physics)
    if noise:
        kwargs["noise"] = NOISE
    correct, wrong = [], []
    with ExitStack() as stack:
        if options:
            tuned = _belief_class(options)
            for module in _BUILDERS:
                stack.enter_context(mock.patch(f"{module}.ParticleBelief", tuned))
        env = gym.make("bounce_gym/BounceLocalization-v0", **kwargs)
        policy = ParticleLocalizationPolicy.for_env(env)
        start = time.perf_counter()
        for seed in seeds:
            began = time.perf_counter()
            summary, _ = run_episode(env, policy, seed, HORIZON)
            info = summary["info"]
            correct.append(bool(info["correct"]))
            wrong.append(bool(info["wrong_claim"]))
            if log is not None:
                print(f"{setting},{seed},{int(correct[-1])},{int(wrong[-1])},{info['claims']},"
                      f"{summary['steps']},{time.perf_counter() - began:.2f}", file=log,
                      flush=True)
        seconds = (time.perf_counter() - start) / len(seeds)
        env.close()
    return {"correct": rate(correct), "wrong": rate(wrong), "seconds": seconds}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settings", default=",".join(SETTINGS),
                        help=f"comma-separated, of {', '.join(SETTINGS)}")
    parser.add_argument("--n", type=int, default=50, help="episodes (seeds) per setting")
    parser.add_argument("--noise", action="store_true",
                        help="reliable rotation noise r = 0.9, eps = 5 deg (default: none)")
    parser.add_argument("--seeds", choices=("tuning", "evaluation"), default="tuning")
    parser.add_argument("--skip", type=int, default=0,
                        help="seeds of the pool skipped before the --n measured (to split a run)")
    parser.add_argument("--particles", type=int, default=DEFAULT_PARTICLES,
                        help="particles of the task's belief and of the policy's")
    parser.add_argument("--physics", choices=("ideal", "dynamic"),
                        help="the pymunk backend with this physics (default: kinematic)")
    parser.add_argument("--log", type=argparse.FileType("w"),
                        help="CSV file of every episode's outcome, written as episodes end")
    args = parser.parse_args(argv)
    names = args.settings.split(",")
    unknown = [name for name in names if name not in SETTINGS]
    if unknown:
        parser.error(f"unknown settings {unknown}; known: {list(SETTINGS)}")
    if args.seeds == "evaluation" and names != ["default"]:
        parser.error("--seeds evaluation measures the defaults only (--settings default)")
    pool = TUNING_SEEDS if args.seeds == "tuning" else EVALUATION_SEEDS
    if not 1 <= args.n <= len(pool) - args.skip or args.skip < 0:
        parser.error(f"--n, --skip: expected 1 to {len(pool)} ({args.seeds} seeds) in all, got "
                     f"{args.n}, {args.skip}")
    seeds = pool[args.skip:args.skip + args.n]
    print(f"seeds {seeds.start}-{seeds.stop - 1} ({args.seeds}), noise {args.noise}, "
          f"{args.particles} particles, {args.physics or 'kinematic'}", flush=True)
    for name in names:
        result = measure(name, seeds, args.noise, args.log, args.particles, args.physics)
        c, w = result["correct"], result["wrong"]
        print(f"{name:<18} correct {c.value:.3f} [{c.lo:.3f}, {c.hi:.3f}] "
              f"wrong {w.value:.3f} [{w.lo:.3f}, {w.hi:.3f}] n {c.n} "
              f"{result['seconds']:.2f} s/episode", flush=True)


if __name__ == "__main__":
    main()
