"""Draw ``docs/continuous_models.png``: one robot in one room, from one start pose, given one
sequence of bounce angles, under the three continuous models — ``kinematic``, ``pymunk`` with
``physics="ideal"`` and ``pymunk`` with ``physics="dynamic"`` (see docs/continuous_models.md),
and the last in the limit in which it converges to the kinematic model.

Each panel joins the robot's rest positions at its bumps (the dots) with straight lines: a robot
drives straight between bumps (the dynamic robot also slides a few centimetres along a wall it
meets at a glancing angle while it brakes, which the lines leave out). The kinematic path is
repeated in grey under the others.

Run from the repository root: ``python docs/make_model_figures.py docs/continuous_models.png``
(a few seconds); ``--bounces N`` sets the number of bounces (default 25).
"""

from __future__ import annotations

import argparse
import io
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bounce_gym.envs.bounce_env import BounceEnv  # noqa: E402
from bounce_gym.files import atomic_write  # noqa: E402
from bounce_gym.worlds import World  # noqa: E402

#: an 8 m x 5 m room (one world unit is a metre) with a 2 m x 1 m pillar
ROOM = World([(0, 0), (8, 0), (8, 5), (0, 5)], holes=[[(3, 2), (5, 2), (5, 3), (3, 3)]],
             name="room_with_pillar")
#: the Create 2's radius, metres: the same disk under every model
RADIUS = 0.17
START = {"position": [1.0, 1.0], "heading": 0.5}
#: the limit in which the dynamic model converges to the kinematic one: instant speed changes and
#: turns, no friction, no rebound (as tests/dynamics/test_pymunk_dynamic.py checks it)
IDEAL_LIMIT = {"max_acceleration": math.inf, "max_speed": math.inf, "turn_rate": math.inf,
               "friction": 0.0, "restitution": 0.0, "control_period": 1e-9}
MODELS = {
    "kinematic": {"backend": "kinematic"},
    "pymunk, physics='ideal'": {"backend": "pymunk", "physics": "ideal"},
    "pymunk, physics='dynamic'": {"backend": "pymunk", "physics": "dynamic"},
    "pymunk, physics='dynamic', ideal limit": {"backend": "pymunk", "physics": "dynamic",
                                               "physics_params": IDEAL_LIMIT},
}
#: Φ = {45°, 90°, 135°}, the envs' default; the sequence of bounce angles is drawn once
ANGLES = (45, 90, 135)
ACTION_SEED = 2


def run(kwargs: dict, actions: np.ndarray) -> tuple[np.ndarray, int]:
    """The robot's rest positions at its bumps (the start first) and the ticks taken."""
    env = BounceEnv(world=ROOM, robot_radius=RADIUS, angles=list(ANGLES), **kwargs)
    env.reset(seed=0, options={"start": START})  # bounce mode: drives to the first bump
    state = env.robot_state
    points = [START["position"], state.position[0].copy()]
    for action in actions.tolist():
        env.step(action)
        points.append(state.position[0].copy())
    ticks = state.ticks
    env.close()
    return np.array(points, dtype=np.float64), ticks


def figure(path: Path, bounces: int) -> Path:
    actions = np.random.default_rng(ACTION_SEED).integers(len(ANGLES), size=bounces)
    runs = {name: run(kwargs, actions) for name, kwargs in MODELS.items()}
    reference = runs["kinematic"][0]
    fig, axes = plt.subplots(2, 2, figsize=(10.4, 8.0))
    colours = ("tab:blue", "tab:green", "tab:red", "tab:purple")
    for ax, (name, (points, ticks)), colour in zip(axes.flat, runs.items(), colours,
                                                   strict=True):
        ax.fill(*ROOM.outer.T, facecolor="#fafaf6", edgecolor="#2c3442", linewidth=2)
        for hole in ROOM.holes:
            ax.fill(*np.asarray(hole).T, facecolor="#a0a6b2", edgecolor="#2c3442", linewidth=2)
        if name != "kinematic":
            ax.plot(*reference.T, color="0.75", linewidth=3, zorder=1, label="kinematic")
        ax.plot(*points.T, color=colour, linewidth=1.2, zorder=2, label="path")
        ax.scatter(*points[1:].T, s=12, color=colour, zorder=3, label="bumps")
        x, y = START["position"]
        heading = START["heading"]
        ax.annotate("", (x + 0.6 * math.cos(heading), y + 0.6 * math.sin(heading)), (x, y),
                    arrowprops={"arrowstyle": "->", "color": "k"}, zorder=4)
        ax.plot(x, y, "ko", markersize=4, zorder=4, label="start")
        gap = float(np.max(np.hypot(*(points - reference).T)))
        versus = ("" if name == "kinematic" else
                  "; bumps identical to kinematic" if gap == 0.0 else
                  f"; bumps up to {gap:.2g} m from kinematic")
        ax.set_title(f"{name}\n{bounces} bounces in {ticks} ticks{versus}", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4, fontsize=7,
                  frameon=False)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    atomic_write(path, buffer.getvalue())
    return path


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", type=Path, help="the PNG to write")
    parser.add_argument("--bounces", type=int, default=25, help="bounces per model")
    args = parser.parse_args(argv)
    if args.bounces < 1:
        parser.error(f"--bounces: expected an integer >= 1, got {args.bounces}")
    written = figure(args.output, args.bounces)
    print(f"{written}: {written.stat().st_size // 1024} KiB")


if __name__ == "__main__":
    main()
