"""Several robots through PettingZoo's parallel API, recorded as a GIF.

``import bounce_gym`` registers the multi-robot ids with PettingZoo, so
``pettingzoo.make("parallel", "bounce_gym/MultiBounceCoverage-v0", ...)`` builds a parallel env:
every step each live robot gets its own action and reward. Here every robot picks a random
bounce angle at every step, each step's picture (``render_mode="rgb_array"``) becomes one GIF
frame (Pillow), and the team's coverage and reward are printed.

Run with ``python examples/pettingzoo_rollout_gif.py`` (``--robots``, ``--steps``, ``--seed``,
``--out FOLDER``; the GIF is ``FOLDER/multi_coverage.gif``, by default in a fresh temporary
folder that is printed at the end).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from bounce_gym.extras import exit_unless_installed

# the extra this example needs, checked before anything imports it
exit_unless_installed("examples/pettingzoo_rollout_gif.py", "pygame", "PIL")

import pettingzoo
from PIL import Image

import bounce_gym  # noqa: F401  (registers the environments)

ENV = "bounce_gym/MultiBounceCoverage-v0"


def rollout(n_robots: int, steps: int, seed: int) -> tuple[list[Image.Image], dict]:
    """The frames of one random-action episode (at most ``steps`` steps) and its totals."""
    env = pettingzoo.make("parallel", ENV, n_robots=n_robots, render_mode="rgb_array")
    observations, infos = env.reset(seed=seed)
    for i, agent in enumerate(env.possible_agents):
        env.action_space(agent).seed(seed + i)  # reproducible random angles
    frames = [Image.fromarray(env.render())]
    total = dict.fromkeys(env.possible_agents, 0.0)
    step = 0
    while env.agents and step < steps:
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)
        for agent, reward in rewards.items():
            total[agent] += float(reward)
        frames.append(Image.fromarray(env.render()))
        step += 1
    env.close()
    last = next(iter(infos.values()), {})
    return frames, {"steps": step, "returns": total, "coverage": last.get("coverage")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=3)
    parser.add_argument("--steps", type=int, default=60, help="at most this many steps")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the GIF (default: a fresh temporary folder)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="pettingzoo_gif_"))
    out.mkdir(parents=True, exist_ok=True)

    frames, summary = rollout(args.robots, args.steps, args.seed)
    path = out / "multi_coverage.gif"
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=100, loop=0)
    print(f"{ENV}, {args.robots} robots, random angles: {summary['steps']} steps, "
          f"coverage {summary['coverage']}")
    print("returns", {agent: round(value, 3) for agent, value in summary["returns"].items()})
    print(f"{len(frames)} frames written to {path}")


if __name__ == "__main__":
    main()
