"""Training speed of the JAX learners (`baselines.rl.jaxrl`) against Stable-Baselines3's.

Run with ``python -m benchmarks.jax_training`` (``--rounds``, ``--ppo-steps``, ``--sb3-steps``,
``--dqn-steps``, ``--episodes``, ``--skip-dqn``). Prints a table; asserts nothing. Issue 26's rows:

* **PPO env steps/s**, ``jax_ppo`` ÷ SB3's ``ppo`` on ``bounce_gym/BounceNavigation-v1`` with the
  same hyperparameters (hyperparams/ppo.yaml's v1 entry: 8 envs, ``n_steps`` 128, mini-batches
  of 256, 10 epochs, separate [64, 64] tanh policy and value nets), target ≥ 20; and on
  ``BounceNavigation-v0`` on the cell backend (the env of ``configs/train_navigation.yaml``:
  a 17-number observation instead of v1's 113) with ppo.yaml's v0 entry, its VecNormalize
  dropped on both sides (jax_ppo has none), to show how the ratio moves with the network's
  input size (the JAX side is bound by its gradient steps' arithmetic). Each side runs
  in a fresh process pinned to one core (``taskset -c 0``; SB3 with one torch thread and its
  native batched env, JAX with ``XLA_FLAGS=--xla_cpu_multi_thread_eigen=false
  intra_op_parallelism_threads=1``). The rate excludes start-up: SB3 learns one rollout before
  the timed ``learn``; JAX runs the compiled chunk once before timing it on a fresh state. The
  sides alternate within a round, the ratio is taken within the round, and the table gives its
  median and min–max over the rounds beside the one-minute load average before and after.
* **DQN with hindsight relabelling to 0.90 success**: ``jax_dqn`` and SB3's ``dqn`` with
  ``HerReplayBuffer``, both with hyperparams/dqn.yaml's v1 entry (``exploration_fraction``
  scaled so that ε still decays over the first 20 k steps of a ``--dqn-steps`` budget), each
  trained once (seed 0) in a process pinned to one core, a checkpoint every
  ``--checkpoint-every`` steps. Afterwards (not timed) every checkpoint plays ``--episodes``
  held-out episodes (seeds from 10,000; sampled actions, the evaluation's default); the row is
  the wall time from the start of training to the first checkpoint whose success is ≥ 0.90, with
  that success and its Wilson interval.
* **PPO end to end at the configured budget** (``--e2e-rounds``, default 5): ``train.py`` on
  configs/train_navigation_v1_ppo.yaml and configs/train_navigation_v1_jax_ppo.yaml (seed 0,
  200 k steps) in fresh processes pinned to one core, start-up and compilation included; JAX
  twice per round in one fresh cache folder, cold then warm (its persistent compilation cache,
  `baselines.rl.jaxrl.compile_cache`); the ratio is SB3's time over JAX's, target ≥ 20 warm.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ENV = "bounce_gym/BounceNavigation-v1"
CONFIGS = Path(__file__).resolve().parents[1] / "configs" / "hyperparams"
#: XLA on one thread (the JAX side of the one-core comparison)
ONE_THREAD_XLA = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
THRESHOLD = 0.90
#: ε decays over this many env steps in both DQN runs (hyperparams/dqn.yaml: 0.2 of 100 k)
EXPLORATION_STEPS = 20_000


#: the PPO rows' tasks: env id, env_kwargs and configuration keys over the hyperparameter
#: file's entry (v0 drops its VecNormalize on both sides: jax_ppo has none)
PPO_TASKS = {
    "v1": (ENV, {}, {}),
    "v0-cell": ("bounce_gym/BounceNavigation-v0",
                {"backend": "cell", "angles": [45, 90, 135],
                 "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}},
                {"normalize": False}),
}


def _ppo_config(algo: str, steps: int, folder: str, task: str = "v1") -> dict:
    env, env_kwargs, keys = PPO_TASKS[task]
    return {"name": "bench", "env": env, "env_kwargs": env_kwargs, "algo": algo,
            "total_timesteps": steps, "seed": 0,
            "hyperparams_file": str(CONFIGS / "ppo.yaml"), "models": folder, **keys}


def _dqn_config(algo: str, steps: int, every: int, folder: str) -> dict:
    return {"name": "bench", "env": ENV, "algo": algo, "total_timesteps": steps, "seed": 0,
            "hyperparams_file": str(CONFIGS / "dqn.yaml"), "models": folder,
            "checkpoint_every": every,
            "hyperparams": {"exploration_fraction": min(1.0, EXPLORATION_STEPS / steps)}}


# -- workers (each in its own pinned process) ---------------------------------------------------
def jax_ppo_rate(steps: int, task: str) -> float:
    import jax

    from baselines.rl.jaxrl.runner import learner
    from baselines.rl.train import prepare

    agent = learner(prepare(_ppo_config("jax_ppo", steps, tempfile.mkdtemp(), task)))
    chunk = agent.chunk(agent.iterations)
    jax.block_until_ready(chunk(agent.init(jax.random.PRNGKey(0))))  # compile
    state = agent.init(jax.random.PRNGKey(1))
    start = time.perf_counter()
    jax.block_until_ready(chunk(state))
    return agent.iterations * agent.steps_per_iteration / (time.perf_counter() - start)


def sb3_ppo_rate(steps: int, task: str) -> float:
    import torch
    from stable_baselines3 import PPO

    from baselines.rl.train import prepare
    from baselines.rl.train_config import algo_kwargs, policy_name
    from baselines.rl.train_env import make_train_env

    torch.set_num_threads(1)
    config = prepare(_ppo_config("ppo", steps, tempfile.mkdtemp(), task))
    env = make_train_env(config, 0)
    model = PPO(policy_name("ppo", env.observation_space), env, seed=0, device="cpu",
                verbose=0, **algo_kwargs(config["hyperparams"]))
    model.learn(1)  # one rollout and update: start-up
    before = model.num_timesteps
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return (model.num_timesteps - before) / (time.perf_counter() - start)


def dqn_run(algo: str, steps: int, every: int, folder: str) -> dict:
    """Train; the seconds from the start to each checkpoint's save."""
    from baselines.rl.train import train

    start = time.time()
    train(_dqn_config(algo, steps, every, folder), progress=False)
    checkpoints = Path(folder) / "bench" / "checkpoints"
    return {p.name: p.stat().st_mtime - start for p in checkpoints.glob("*_steps.zip")}


def _pinned(args: list[str]) -> object:
    """Run a worker of this module on core 0 (one thread) and return what it prints (JSON)."""
    env = {**os.environ, "XLA_FLAGS": ONE_THREAD_XLA, "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    command = [sys.executable, "-m", "benchmarks.jax_training", "--worker", *args]
    if shutil.which("taskset"):
        command = ["taskset", "-c", "0", *command]
    out = subprocess.run(command, env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


# -- the measurements --------------------------------------------------------------------------
def ppo_rows(rounds: int, jax_steps: int, sb3_steps: int, task: str = "v1") -> None:
    load_before = os.getloadavg()[0]
    rates = {"jax_ppo": [], "ppo": []}
    for _ in range(rounds):
        rates["jax_ppo"].append(_pinned(["jax_ppo", str(jax_steps), task]))
        rates["ppo"].append(_pinned(["ppo", str(sb3_steps), task]))
    ratios = [j / s for j, s in zip(rates["jax_ppo"], rates["ppo"], strict=True)]
    load_after = os.getloadavg()[0]
    env, env_kwargs, keys = PPO_TASKS[task]
    print(f"PPO on {env} {env_kwargs or ''} {keys or ''}, one core each, {rounds} rounds "
          f"(load {load_before:.2f} before, {load_after:.2f} after)")
    for name, values in rates.items():
        print(f"  {name:<8} env steps/s  median {statistics.median(values):>9,.0f}  "
              f"min–max {min(values):,.0f}–{max(values):,.0f}")
    verdict = "ok" if statistics.median(ratios) >= 20 else "below target"
    print(f"  jax_ppo ÷ ppo (within a round)  median {statistics.median(ratios):.1f}  "
          f"min–max {min(ratios):.1f}–{max(ratios):.1f}  target ≥ 20: {verdict}")


#: the end-to-end rows' training configurations (configs/): the v1 budget as shipped
E2E_CONFIGS = {"jax_ppo": "train_navigation_v1_jax_ppo.yaml", "ppo": "train_navigation_v1_ppo.yaml"}
ROOT = Path(__file__).resolve().parents[1]


def _train_seconds(algo: str, cache: str, folder: str) -> float:
    """Wall seconds of ``train.py`` on the shipped configuration of ``algo`` (seed 0, its
    budget) in a fresh process pinned to core 0, start-up and compilation included, with
    ``cache`` as ``$BOUNCE_GYM_CACHE`` (the JAX compilation cache lives there)."""
    import yaml

    config = yaml.safe_load((ROOT / "configs" / E2E_CONFIGS[algo]).read_text(encoding="utf-8"))
    config.update(models=folder, seeds=[0],
                  hyperparams_file=str(ROOT / "configs" / config["hyperparams_file"]))
    path = Path(folder) / f"{algo}.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    env = {**os.environ, "XLA_FLAGS": ONE_THREAD_XLA, "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "BOUNCE_GYM_CACHE": cache}
    command = [sys.executable, str(ROOT / "train.py"), str(path), "--no-progress"]
    if shutil.which("taskset"):
        command = ["taskset", "-c", "0", *command]
    start = time.perf_counter()
    subprocess.run(command, env=env, check=True, capture_output=True, cwd=folder)
    return time.perf_counter() - start


def end_to_end_rows(rounds: int) -> None:
    """PPO on v1 at the configured budget, end to end: per round, SB3 once and JAX twice in
    one fresh cache folder — cold (every program compiled) and warm (read from JAX's
    persistent compilation cache, `baselines.rl.jaxrl.compile_cache`)."""
    load_before = os.getloadavg()[0]
    times: dict[str, list[float]] = {"ppo": [], "jax_ppo cold": [], "jax_ppo warm": []}
    for _ in range(rounds):
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as folder:
            times["ppo"].append(_train_seconds("ppo", cache, folder))
            for kind in ("cold", "warm"):
                shutil.rmtree(Path(folder) / "navigation-lab-v1", ignore_errors=True)
                times[f"jax_ppo {kind}"].append(_train_seconds("jax_ppo", cache, folder))
    print(f"PPO on {ENV} end to end at the configured budget (train.py, seed 0, fresh process, "
          f"one core), {rounds} rounds (load {load_before:.2f} before, "
          f"{os.getloadavg()[0]:.2f} after)")
    for name, values in times.items():
        print(f"  {name:<13} s  median {statistics.median(values):>7.1f}  "
              f"min–max {min(values):.1f}–{max(values):.1f}")
    for kind in ("cold", "warm"):
        ratios = [s / j for s, j in zip(times["ppo"], times[f"jax_ppo {kind}"], strict=True)]
        verdict = "ok" if statistics.median(ratios) >= 20 else "below target"
        print(f"  ppo ÷ jax_ppo {kind} (time, within a round)  median "
              f"{statistics.median(ratios):.1f}  min–max {min(ratios):.1f}–{max(ratios):.1f}"
              + (f"  target ≥ 20: {verdict}" if kind == "warm" else ""))


def _success(path: Path, episodes: int) -> int:
    import gymnasium as gym

    from baselines.rl.model_files import JAX_ALGOS, read_model
    from baselines.rl.policies import SB3Policy
    from baselines.seeds import EVALUATION_SEEDS_START
    from bounce_gym_experiments.runner import run_episode

    env = gym.make(ENV)
    if read_model(path).algo in JAX_ALGOS:
        from baselines.rl.jaxrl.policy import JaxPolicy

        policy = JaxPolicy(path, env)
    else:
        policy = SB3Policy(path, env)
    seeds = range(EVALUATION_SEEDS_START, EVALUATION_SEEDS_START + episodes)
    return sum(bool(run_episode(env, policy, seed, 10**6)[0]["info"]["is_success"])
               for seed in seeds)


def dqn_rows(steps: int, every: int, episodes: int) -> None:
    from baselines.rl.model_files import CHECKPOINT_NAME
    from bounce_gym_experiments.stats import wilson_interval

    print(f"DQN + hindsight relabelling on {ENV} to success ≥ {THRESHOLD} ({episodes} held-out "
          f"episodes per checkpoint, one run each, seed 0, one core; load "
          f"{os.getloadavg()[0]:.2f})")
    for algo in ("jax_dqn", "dqn"):
        with tempfile.TemporaryDirectory() as folder:
            times = _pinned(["dqn", algo, str(steps), str(every), folder])
            found = None
            for name, seconds in sorted(times.items(), key=lambda item: int(
                    CHECKPOINT_NAME.fullmatch(item[0])["steps"])):
                reached = _success(Path(folder) / "bench" / "checkpoints" / name, episodes)
                at = int(CHECKPOINT_NAME.fullmatch(name)["steps"])
                low, high = wilson_interval(reached, episodes)
                print(f"  {algo:<8} {at:>7} steps  {seconds:>7.1f} s  success "
                      f"{reached / episodes:.3f} [{low:.3f}, {high:.3f}]")
                if reached / episodes >= THRESHOLD:
                    found = (at, seconds)
                    break
            print(f"  {algo:<8} reaches {THRESHOLD}: "
                  + (f"at {found[0]} steps, {found[1]:.1f} s" if found else
                     f"not within {steps} steps"))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--ppo-steps", type=int, default=204_800)
    parser.add_argument("--sb3-steps", type=int, default=10_240)
    parser.add_argument("--dqn-steps", type=int, default=50_000)
    parser.add_argument("--checkpoint-every", type=int, default=5_000)
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--skip-dqn", action="store_true")
    parser.add_argument("--e2e-rounds", type=int, default=5,
                        help="rounds of the end-to-end rows (0: none)")
    args = parser.parse_args(argv)
    if args.worker:
        kind, *rest = args.worker
        if kind == "dqn":
            print(json.dumps(dqn_run(rest[0], int(rest[1]), int(rest[2]), rest[3])))
        else:
            rate = jax_ppo_rate if kind == "jax_ppo" else sb3_ppo_rate
            print(json.dumps(rate(int(rest[0]), rest[1])))
        return
    for task in PPO_TASKS:
        ppo_rows(args.rounds, args.ppo_steps, args.sb3_steps, task)
    if args.e2e_rounds:
        end_to_end_rows(args.e2e_rounds)
    if not args.skip_dqn:
        dqn_rows(args.dqn_steps, args.checkpoint_every, args.episodes)


if __name__ == "__main__":
    main()
