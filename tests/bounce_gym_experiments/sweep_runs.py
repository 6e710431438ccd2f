"""A small evaluation for the sweep tests (imported by name, see conftest.py): four families on
12 seeds each, so every policy is two units; and running it through ``evaluate.py`` into a
folder of its own, reporting the checksums of its ``episodes.csv`` and ``results.json``."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import yaml

from bounce_gym_experiments.config import load_config
from bounce_gym_experiments.run_folders import finished_runs

ROOT = Path(__file__).parents[2]
#: experiments of the default configuration: fixed angles with the best in hindsight, patrols
#: (captures filed with the setup, a note), a visibility scenario (the setup as plot data), a
#: drifter (plot data of the env's cell model)
EXPERIMENTS = ("localization-lab", "patrol-10x10", "visibility-patrol-heptagon", "drifter-reach")
SEEDS = 12


def write_config(folder: Path, name: str = "sweep") -> Path:
    """The small evaluation as ``folder/<name>.yaml``, writing into ``folder/runs``."""
    shipped = {e["name"]: e for e in load_config()["experiments"]}
    experiments = [dict(shipped[n], seeds={"start": 10_000, "count": SEEDS})
                   for n in EXPERIMENTS]
    config = {"name": name, "output": str(folder / "runs"), "models": str(folder / "models"),
              "experiments": experiments}
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    return path


def checksums(run: Path) -> dict[str, str]:
    """sha256 of a run folder's episodes.csv and results.json."""
    return {f: hashlib.sha256((run / f).read_bytes()).hexdigest()
            for f in ("episodes.csv", "results.json")}


def take_run(folder: Path, label: str) -> Path:
    """Move the one run folder in ``folder/runs`` to ``folder/<label>`` (so that the next run
    of the same configuration writes a folder of its own) and return its new place."""
    (run,) = finished_runs(folder / "runs")
    return Path(shutil.move(str(run), str(folder / label)))
