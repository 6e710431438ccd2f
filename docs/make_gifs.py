"""Record the docs' pictures: one short episode of each environment as a GIF.

Run from the repository root: ``.venv/bin/python docs/make_gifs.py`` (writes ``docs/*.gif``).
"""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import gymnasium as gym
import numpy as np

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceEnv
from bounce_gym.envs.render.gif import record_episode, save_gif

HERE = Path(__file__).parent
WIDTH = 360


def single_robot_gifs() -> None:
    runs = {
        "bounce.gif": ("bounce_gym/Bounce-v0", {"step_mode": "tick"}, 70),
        "navigation.gif": ("bounce_gym/BounceNavigation-v0", {"step_mode": "tick"}, 70),
        "coverage.gif": ("bounce_gym/BounceCoverage-v0", {}, 40),
    }
    for name, (env_id, kwargs, steps) in runs.items():
        env = gym.make(env_id, render_mode="rgb_array", **kwargs)
        record_episode(env, None, HERE / name, max_steps=steps, seed=1, fps=12, width=WIDTH)
        env.close()


def multi_robot_gif() -> None:
    env = MultiBounceEnv(world="grid_20x12", n_robots=4, task="monitoring", robot_radius=0.4,
                         step_mode="tick", render_mode="rgb_array")
    env.reset(seed=1)
    rng = np.random.default_rng(1)
    frames = [env.render()]
    for _ in range(70):
        env.step({a: int(rng.integers(3)) for a in env.agents})
        frames.append(env.render())
    save_gif(frames, HERE / "multi_monitoring.gif", fps=12, width=WIDTH)


def drifter_gif() -> None:
    """Four drifters on the scb_like currents (continuous backend, 1 h steps): the surface
    current as streamlines, the cells they have visited, and a drifter that dives and rises."""
    env = MultiDrifterEnv(flow="scb_like", backend="continuous", step_seconds=3600.0,
                          deploy=[(0, 15, 3), (0, 10, 10), (0, 4, 8), (0, 12, 20)],
                          field_style="streamlines", render_mode="rgb_array")
    env.reset(seed=1)
    frames = [env.render()]
    for k in range(24):
        dive = 2 if k == 6 else 1 if k == 14 else 0  # drifter_1 spends 8 h one layer down
        env.step({a: dive if a == "drifter_1" else 0 for a in env.agents})
        frames.append(env.render())
    save_gif(frames, HERE / "drifters.gif", fps=6, width=WIDTH)


if __name__ == "__main__":
    single_robot_gifs()
    multi_robot_gif()
    drifter_gif()
    for gif in sorted(HERE.glob("*.gif")):
        print(f"{gif.name}: {gif.stat().st_size // 1024} KiB")
