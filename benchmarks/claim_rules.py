"""Claim rules of the particle localization filter, scored on recorded beliefs (tuning seeds).

Run with ``python -m benchmarks.claim_rules --n 50``. A claim changes neither the beliefs nor
the policy's actions (the policy keeps its own particles), so an episode run to the horizon
without terminating records everything every rule would see: at each bump, for the task's
main belief and for one independent replica fed the same angles and clocks, the most likely
decision state, its mass, the effective sample size and where the particles of the last bump's
most likely state went (`ParticleBelief.successors`). Each rule is then replayed on the record:
its first claim is the claim of an episode that terminates there, judged against the true
state at that bump. The settings are those of `benchmarks.particle_tuning` (lab_localization_a,
kinematic, Φ = {45°, 135°}, reliable rotation noise r = 0.9, ε = 5°); the seeds are the first
``--n`` of `baselines.seeds.TUNING_SEEDS` (``--skip`` to split a run). ``--record`` saves the
records (one .npy per seed) and ``--score`` scores saved ones, so runs can be split.
"""

from __future__ import annotations

import argparse
import glob
import itertools
from pathlib import Path

import gymnasium as gym
import numpy as np

import bounce_gym  # noqa: F401  (registers the envs)
from baselines.localization import ParticleLocalizationPolicy
from baselines.seeds import TUNING_SEEDS
from benchmarks.particle_tuning import NOISE
from bounce_gym.dynamics.particles import ParticleBelief
from bounce_gym_experiments.stats import rate

#: bumps per recorded episode
HORIZON = 150
#: record columns: truth, then per belief (main, replica): state, mass, ess share,
#: followed mass, followed state
TRUTH = 0


def _followed(belief: ParticleBelief, before: int | None) -> tuple[float, int]:
    if before is None:
        return 0.0, -1
    states, mass = belief.successors(before)
    mass = np.where(states >= 0, mass, 0.0)
    return (float(mass.max()), int(states[np.argmax(mass)])) if mass.size else (0.0, -1)


def record(seed: int, particles: int) -> np.ndarray:
    """One episode to the horizon: a row per bump (module docstring)."""
    env = gym.make("bounce_gym/BounceLocalization-v0", backend="kinematic", angles=[45, 135],
                   noise=NOISE, max_episode_steps=HORIZON,
                   task_kwargs={"filter_factory": "particles", "particles": particles,
                                "terminate_when_localized": False, "claim_replicas": 1})
    policy = ParticleLocalizationPolicy.for_env(env)
    base = env.unwrapped
    policy.start_options(env, seed)
    obs, _ = env.reset(seed=seed)
    policy.reset(env)
    beliefs, before, rows = base.task.filter.beliefs, [None, None], []
    for _ in range(HORIZON):
        obs, _, terminated, truncated, _ = env.step(policy.act(obs, None))
        state = base.core.state
        row = [base.task.states.of(state.position[:1], state.heading[:1],
                                   state.contact_normal[:1])[0]]
        for i, belief in enumerate(beliefs):
            row += [belief.most_likely, belief.max_mass, belief.ess / belief.n,
                    *_followed(belief, before[i])]
            before[i] = belief.most_likely
        rows.append(row)
        if terminated or truncated:
            break
    env.close()
    return np.array(rows, dtype=np.float64)


def first_claim(rows: np.ndarray, threshold: float, ess: float, bumps: int,
                replicas: int) -> int | None:
    """The bump of a rule's first claim (`ParticleClaims`' rule, replayed), or None."""
    streak = 0
    for i, row in enumerate(rows):
        parts = [row[1 + 5 * b: 6 + 5 * b] for b in range(1 + replicas)]
        evident = len({p[0] for p in parts}) == 1 \
            and all(p[1] >= threshold and p[2] >= ess for p in parts)
        followed = all(p[3] >= threshold and p[4] == p[0] and p[2] >= ess for p in parts)
        streak = streak + 1 if evident and streak > 0 and followed else int(evident)
        if streak >= bumps:
            return i
    return None


def score(records: dict[int, np.ndarray]) -> None:
    print("| replicas | threshold | ESS floor | bumps | correct | wrong (count) | mean steps |")
    print("|---|---|---|---|---|---|---|")
    for replicas, threshold, ess, bumps in itertools.product((0, 1), (0.99, 0.999), (0.0, 0.1),
                                                             (1, 2, 3, 5)):
        correct, wrong, steps = [], [], []
        for rows in records.values():
            i = first_claim(rows, threshold, ess, bumps, replicas)
            right = i is not None and rows[i][1] == rows[i][TRUTH]
            correct.append(right)
            wrong.append(i is not None and not right)
            steps.append(len(rows) if i is None else i + 1)
        c, w = rate(correct), rate(wrong)
        print(f"| {replicas} | {threshold} | {ess} | {bumps} | {c.value:.3f} [{c.lo:.3f}, "
              f"{c.hi:.3f}] | {w.value:.3f} [{w.lo:.3f}, {w.hi:.3f}] ({sum(wrong)}) | "
              f"{np.mean(steps):.0f} |", flush=True)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=50)
    parser.add_argument("--skip", type=int, default=0)
    parser.add_argument("--particles", type=int, default=1000)
    parser.add_argument("--record", type=Path, help="folder to save the records in")
    parser.add_argument("--score", type=Path, help="score the records saved in this folder")
    args = parser.parse_args(argv)
    if args.score is not None:
        files = sorted(glob.glob(str(args.score / "*.npy")))
        records = {int(Path(f).stem): np.load(f) for f in files}
        if not all(seed in TUNING_SEEDS for seed in records):
            parser.error("the records must come from tuning seeds")
    else:
        records = {}
        for seed in TUNING_SEEDS[args.skip:args.skip + args.n]:
            records[seed] = record(seed, args.particles)
            if args.record is not None:
                args.record.mkdir(parents=True, exist_ok=True)
                np.save(args.record / f"{seed}.npy", records[seed])
    print(f"{len(records)} episodes, tuning seeds {min(records)}-{max(records)}")
    score(records)


if __name__ == "__main__":
    main()
