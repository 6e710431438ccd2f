"""Train Stable-Baselines3's PPO on the package's own batched env, then score it.

``gym.make_vec(..., vectorization_mode="vector_entry_point")`` builds one
`bounce_gym.envs.vector_env.BounceVectorEnv` that steps all its robots at once; on the
``cell`` backend no physics engine runs. SB3 takes only its own ``VecEnv`` type, so the
vector env is wrapped in `baselines.rl.vector_vec_env.VectorToVecEnv`, which turns
Gymnasium's next-step autoreset into SB3's same-step reset. Training seeds lie below 10,000.
The model then plays sampled actions on one env for held-out episode seeds from 10,000 on,
and the success rate is printed with its 95 % Wilson interval.

Run with ``python examples/sb3_native_vector_env.py`` (``--steps``, ``--episodes``,
``--out FOLDER``; the model is saved as ``FOLDER/ppo_navigation.zip``, by default in a fresh
temporary folder that is printed at the end).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from bounce_gym.extras import exit_unless_installed

# the extra this example needs, checked before anything imports it (rich, with the tqdm that
# the extra also installs, draws SB3's progress bar)
exit_unless_installed("examples/sb3_native_vector_env.py", "stable_baselines3", "torch", "rich")

import gymnasium as gym
import torch
from stable_baselines3 import PPO

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.rl.vector_vec_env import VectorToVecEnv
from baselines.seeds import EVALUATION_SEEDS_START
from bounce_gym_experiments.stats import wilson_interval

ENV = "bounce_gym/BounceNavigation-v0"
ENV_KWARGS = {"backend": "cell"}
N_ENVS = 8


def train(steps: int, seed: int) -> PPO:
    """PPO trained ``steps`` env steps on ``N_ENVS`` robots of one native vector env."""
    vector = gym.make_vec(ENV, num_envs=N_ENVS, vectorization_mode="vector_entry_point",
                          **ENV_KWARGS)
    venv = VectorToVecEnv(vector)
    venv.seed(seed)  # env i starts from seed + i: training seeds stay below 10,000
    # one thread for a small MLP on small batches, as `baselines.rl.train` trains by default
    # (torch_threads: 1): more only contend with the env and, on a busy machine, spin
    torch.set_num_threads(1)
    model = PPO("MlpPolicy", venv, n_steps=128, batch_size=256, seed=seed, verbose=0)
    return model.learn(total_timesteps=steps, progress_bar=True)


def successes(model: PPO, episodes: int) -> int:
    """How many held-out episodes (seeds from 10,000) end at the goal, actions sampled."""
    env = gym.make(ENV, **ENV_KWARGS)
    reached = 0
    for seed in range(EVALUATION_SEEDS_START, EVALUATION_SEEDS_START + episodes):
        obs, info = env.reset(seed=seed)
        done = False
        while not done:
            action, _ = model.predict(obs, deterministic=False)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
        reached += bool(info["is_success"])
    env.close()
    return reached


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100_000, help="training env steps")
    parser.add_argument("--episodes", type=int, default=200, help="held-out episodes")
    parser.add_argument("--seed", type=int, default=0, help="training seed (< 10,000 - 8)")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the model (default: a fresh temporary folder)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="sb3_native_"))
    out.mkdir(parents=True, exist_ok=True)

    start = time.perf_counter()
    model = train(args.steps, args.seed)
    seconds = time.perf_counter() - start
    model.save(out / "ppo_navigation.zip")
    reached = successes(model, args.episodes)
    low, high = wilson_interval(reached, args.episodes)
    print(f"PPO on {ENV} {ENV_KWARGS}, {N_ENVS} envs in one native vector env: "
          f"{args.steps} steps in {seconds:.1f} s")
    print(f"success {reached / args.episodes:.3f} [{low:.3f}, {high:.3f}] "
          f"n={args.episodes} held-out episodes (sampled actions)")
    print(f"model saved in {out}")


if __name__ == "__main__":
    main()
