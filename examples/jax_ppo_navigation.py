"""Train PPO written in JAX on ``bounce_gym/BounceNavigation-v1`` on the CPU, then score it.

Run with ``python examples/jax_ppo_navigation.py`` (``--steps``, ``--episodes``, ``--out FOLDER``;
the run is ``FOLDER/jax-ppo-example/``, by default in a fresh temporary folder). It trains
the ``jax_ppo`` configuration of ``configs/train_navigation_v1_jax_ppo.yaml`` (one seed, the
hyperparameters of SB3's PPO entry for v1: 8 envs, 128 steps each per rollout, 10 epochs of
256-transition mini-batches) through ``baselines.rl.train`` into that folder, printing the
steps done after each chunk of iterations (up to 16,384 steps, one compiled call), then plays
the model's sampled actions (the evaluation's default) on held-out episode seeds (from 10,000)
of the NumPy env and prints the success rate with its 95 % Wilson interval and the wall time.
"""

from __future__ import annotations

import argparse
import contextlib
import tempfile
import time
from pathlib import Path

from bounce_gym.extras import exit_unless_installed

# the extra this example needs, checked before anything imports it
exit_unless_installed("examples/jax_ppo_navigation.py", "jax", "optax")

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.rl.jaxrl.policy import JaxPolicy
from baselines.rl.train import train
from baselines.seeds import EVALUATION_SEEDS_START
from bounce_gym_experiments.runner import run_episode
from bounce_gym_experiments.stats import wilson_interval

ENV = "bounce_gym/BounceNavigation-v1"
#: more steps than any episode takes (the env's horizon ends it first)
MAX_STEPS = 10**6
HYPERPARAMS = Path(__file__).resolve().parents[1] / "configs" / "hyperparams" / "ppo.yaml"


def success(path: Path, episodes: int) -> int:
    """How many of ``episodes`` held-out episodes the model at ``path`` ends at its goal."""
    env = gym.make(ENV)
    policy = JaxPolicy(path, env)
    seeds = range(EVALUATION_SEEDS_START, EVALUATION_SEEDS_START + episodes)
    # the evaluation's own episode loop (the policy acts on the observation only)
    return sum(bool(run_episode(env, policy, seed, MAX_STEPS)[0]["info"]["is_success"])
               for seed in seeds)


def train_and_score(steps: int = 200_000, episodes: int = 200, seed: int = 0,
                    out: Path | None = None) -> dict:
    """Train ``steps`` env steps into the models folder ``out`` (None: a temporary folder,
    removed afterwards), score on ``episodes`` held-out seeds: the success rate, its Wilson
    interval, the seconds training took (compiling included) and the model's path. Training
    prints a line per chunk of iterations (the runner's progress)."""
    with contextlib.ExitStack() as stack:
        folder = out if out is not None else stack.enter_context(tempfile.TemporaryDirectory())
        start = time.perf_counter()
        (path,) = train({"name": "jax-ppo-example", "env": ENV, "algo": "jax_ppo",
                         "hyperparams_file": str(HYPERPARAMS), "total_timesteps": steps,
                         "seed": seed, "models": str(folder)}, log=print)
        seconds = time.perf_counter() - start
        reached = success(path, episodes)
    return {"success": reached / episodes, "interval": wilson_interval(reached, episodes),
            "episodes": episodes, "train_seconds": seconds, "model": path}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--out", type=Path, default=None,
                        help="models folder of the run (default: a fresh temporary folder)")
    args = parser.parse_args()
    folder = args.out or Path(tempfile.mkdtemp(prefix="jax_ppo_"))
    folder.mkdir(parents=True, exist_ok=True)
    out = train_and_score(args.steps, args.episodes, out=folder)
    low, high = out["interval"]
    print(f"jax_ppo on {ENV}: {args.steps} steps in {out['train_seconds']:.1f} s; success "
          f"{out['success']:.3f} [{low:.3f}, {high:.3f}] over {out['episodes']} held-out "
          "episodes (sampled actions)")
    print(f"model written to {out['model']}")


if __name__ == "__main__":
    main()
