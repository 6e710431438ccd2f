"""Throughput of the native batched env (`BounceVectorEnv`); ratios against anchors of the same run.

Run with ``python -m benchmarks.vector_env``. Prints one row per ratio with its target; asserts
nothing. Rates are the best of ``repeats`` runs (time.perf_counter):

* robot-bounces/s of ``gym.make_vec("bounce_gym/Bounce-v0", 1024)`` ÷ `BounceDynamics.bounce_each`
  with 1,024 robots in two_rooms (the dynamics alone; target ≥ 0.5);
* env-steps/s of the native env at N = 64 ÷ ``vectorization_mode="sync"`` at N = 64
  (target ≥ 100);
* env-steps/s of the native env on the cell backend at N = 1,024 (``BounceNavigation-v0``, angles
  45°, 90°, 135°, goal radius 0.3, heading tolerance 10°, random actions, episodes ending by goal
  and by time, so resets included) ÷ ``vectorization_mode="sync"`` of the same env at N = 64
  (target ≥ 100);
* PPO training env-steps/s on ``configs/train_navigation.yaml`` through the SB3 view of the
  native env ÷ through SB3's DummyVecEnv of ``gym.make`` copies (4,096 steps, torch on one
  thread; target ≥ 5). Both run as `baselines.rl.train.train` runs them (monitor file,
  VecNormalize, the configuration's hyperparameters), timed from the first to the last step of
  learning.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np

import bounce_gym  # noqa: F401
from bounce_gym import worlds
from bounce_gym.documents import read_document

ID = "bounce_gym/Bounce-v0"
CONFIG = Path(__file__).resolve().parent.parent / "configs" / "train_navigation.yaml"


#: the cell-backend navigation configuration of the third row
CELL_NAVIGATION = ("bounce_gym/BounceNavigation-v0",
                   {"backend": "cell", "angles": [45, 90, 135],
                    "task_kwargs": {"goal_radius": 0.3, "heading_tolerance_deg": 10}})


def vector_steps(n: int, steps: int, mode: str, env_id: str = ID,
                 kwargs: dict | None = None) -> Callable[[], int]:
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode=mode, **(kwargs or {}))
    env.reset(seed=0)
    actions = np.random.default_rng(1).integers(0, 3, (steps, n))

    def run() -> int:
        for row in actions:
            env.step(row)
        return steps * n

    return run


def ppo_rate(vec_env: str, steps: int, config_path: Path = CONFIG) -> float:
    """Env steps per second of PPO learning ``steps`` steps with a training configuration (one
    seed, no checkpoint), as `baselines.rl.train.train` runs it; building and saving the model
    are not timed."""
    from stable_baselines3.common.callbacks import BaseCallback

    from baselines.rl.train import train

    class Timer(BaseCallback):
        def _on_training_start(self) -> None:
            self.start, self.first = time.perf_counter(), self.model.num_timesteps

        def _on_training_end(self) -> None:
            self.rate = (self.model.num_timesteps - self.first) / (time.perf_counter()
                                                                   - self.start)

        def _on_step(self) -> bool:
            return True

    timer = Timer()
    config = read_document(config_path, "config")
    config.pop("seed", None)
    with tempfile.TemporaryDirectory() as models:
        train({**config, "vec_env": vec_env, "total_timesteps": steps, "seeds": [0],
               "checkpoint_every": 0, "models": models}, progress=False, callbacks=[timer],
              folder=config_path.parent)
    return timer.rate


def _row(name: str, ratio: float, target: float) -> None:
    verdict = "ok" if ratio >= target else "below target"
    print(f"{name:<58} {ratio:>9.2f}  target >= {target:g}  {verdict}")


def main(quick: bool = False, repeats: int = 3) -> None:
    from benchmarks.run import _time as _best_rate  # imported here: run.py imports this module
    from benchmarks.run import independent_robots

    rounds = 20 if quick else 100
    anchor = _best_rate(lambda: independent_robots(worlds.get("two_rooms"), 1024, rounds),
                        repeats)
    native = _best_rate(lambda: vector_steps(1024, rounds, "vector_entry_point"), repeats)
    print(f"bounce_each, 1,024 robots: {anchor:,.0f} robot-bounces/s; "
          f"vector env N = 1,024: {native:,.0f}")
    _row("vector env N=1024 / bounce_each 1024 robots", native / anchor, 0.5)
    steps = 20 if quick else 100
    fast = _best_rate(lambda: vector_steps(64, steps, "vector_entry_point"), repeats)
    slow = _best_rate(lambda: vector_steps(64, max(steps // 5, 4), "sync"), repeats)
    print(f"N = 64 env-steps/s: native {fast:,.0f}, sync {slow:,.0f}")
    _row("vector env N=64 / make_vec sync N=64", fast / slow, 100)
    cell_steps = 100 if quick else 600  # past the registered 200-step limit: truncations too
    fast = _best_rate(lambda: vector_steps(1024, cell_steps, "vector_entry_point",
                                           *CELL_NAVIGATION), repeats)
    slow = _best_rate(lambda: vector_steps(64, max(cell_steps // 10, 10), "sync",
                                           *CELL_NAVIGATION), repeats)
    print(f"cell navigation env-steps/s: native N = 1,024 {fast:,.0f}, sync N = 64 {slow:,.0f}")
    _row("vector env cell nav N=1024 / make_vec sync N=64", fast / slow, 100)
    ppo_steps = 1024 if quick else 4096
    ours, theirs = ppo_rate("native", ppo_steps), ppo_rate("sync", ppo_steps)
    print(f"PPO env-steps/s: native view {ours:,.0f}, DummyVecEnv {theirs:,.0f}")
    _row("PPO train_navigation native view / DummyVecEnv", ours / theirs, 5)


if __name__ == "__main__":
    main()
