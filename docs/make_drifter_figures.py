"""Draw the drifter figures of docs/drifters.md: the value-iteration policy of ``Drifter-v0`` and the
surface coverage of the deployments in ``configs/eval_drifters.yaml``.

Run from the repository root: ``.venv/bin/python docs/make_drifter_figures.py`` (writes
``docs/drifter_policy.png`` and ``docs/drifter_coverage.png``; about 10 s).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.drifters import ValueIterationPolicy
from bounce_gym.files import atomic_write
from bounce_gym_experiments.config import configs_folder, load_config
from bounce_gym_experiments.plots.drifters import plot_policy
from bounce_gym_experiments.report import write_plots
from bounce_gym_experiments.runner import run

HERE = Path(__file__).parent
#: the experiment of configs/eval_drifters.yaml whose coverage plot docs/drifters.md shows
DEPLOYMENT = "drifter-deployment-two-sink"


def policy_figure() -> Path:
    """Alg. 5.5 for the registered goal of Drifter-v0, on its cell model."""
    env = gym.make("bounce_gym/Drifter-v0")
    env.reset(seed=0)
    planner = ValueIterationPolicy()
    planner.reset(env)
    path = plot_policy(env.unwrapped.cell_model(), planner.result, HERE / "drifter_policy.png",
                       title="Drifter-v0 (scb_like): Alg. 5.5 policy to the 3 x 3 goal "
                             "(gold stars)")
    env.close()
    return path


def coverage_figure() -> Path:
    """The coverage-vs-steps plot of the evaluation's two_sink deployment experiment."""
    config = load_config(configs_folder() / "eval_drifters.yaml")
    config["experiments"] = [e for e in config["experiments"] if e["name"] == DEPLOYMENT]
    _, plots = run(config, progress=False)
    with tempfile.TemporaryDirectory() as folder:
        write_plots(Path(folder), plots)
        figure = (Path(folder) / f"{DEPLOYMENT}-coverage.png").read_bytes()
    path = HERE / "drifter_coverage.png"
    atomic_write(path, figure)
    return path


if __name__ == "__main__":
    for written in (policy_figure(), coverage_figure()):
        print(f"{written.name}: {written.stat().st_size // 1024} KiB")
