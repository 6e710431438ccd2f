"""The wheel: it carries what an installed `bounce-gym evaluate` reads — the shipped
configurations, the trained agents (`baselines.shipped_agents`) and the bump tables
(`bounce_gym.dynamics.bump_table.SHIPPED_TABLES`) — and, installed into a fresh virtual
environment with the ``experiments`` and ``rl`` extras (slow), it plays a trained agent's row
from a folder outside the checkout."""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).parents[1]


def _tracked_files() -> list[str]:
    done = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True)
    return [name for name in done.stdout.decode().split("\0") if name]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel built from the checkout's tracked files (as a clean clone has them)."""
    source, out = tmp_path_factory.mktemp("source"), tmp_path_factory.mktemp("wheel")
    for name in _tracked_files():
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / name, source / name)
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps",
                           "--no-build-isolation", ".", "-w", str(out)], cwd=source,
                          capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    (built,) = out.glob("*.whl")
    return built


def test_the_wheel_carries_the_agents_tables_and_configurations(wheel):
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    tracked = _tracked_files()
    for prefix in ("baselines/agents/", "bounce_gym/dynamics/tables/"):
        shipped = {name for name in tracked if name.startswith(prefix)}
        assert shipped and shipped <= names, sorted(shipped - names)[:5]
    configs = {f"bounce_gym_experiments/{name}" for name in tracked
               if name.startswith("configs/") and name.endswith((".yaml", ".json"))}
    assert configs <= names, sorted(configs - names)[:5]


@pytest.mark.slow
def test_an_installed_wheel_plays_a_trained_agent_outside_the_checkout(wheel, tmp_path):
    """``pip install <wheel>[experiments,rl]`` (constraints.txt) into a new virtual
    environment, then ``bounce-gym evaluate`` in an empty folder: the shipped MAPPO/IPPO agents
    of multi-robot monitoring play beside random bouncing (``models: baselines/agents``)."""
    venv.EnvBuilder(with_pip=True).create(tmp_path / "venv")
    bin_folder = tmp_path / "venv" / "bin"
    # pip's own settings only (where it finds wheels), none that could show it another install
    # of the package (PYTHONPATH, a virtual environment's variables)
    clean = {"PATH": f"{bin_folder}:/usr/bin:/bin", "HOME": str(tmp_path),
             **{k: v for k, v in os.environ.items() if k.startswith("PIP_") or k == "TMPDIR"}}
    done = subprocess.run([str(bin_folder / "python"), "-m", "pip", "install", "-q", "-c",
                           str(ROOT / "constraints.txt"), f"{wheel}[experiments,rl]"],
                          capture_output=True, text=True, timeout=1800, check=False, env=clean)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (bin_folder / "bounce-gym").is_file(), done.stdout[-3000:]
    default = yaml.safe_load((ROOT / "configs" / "eval_default.yaml").read_text())
    (experiment,) = [exp for exp in default["experiments"]
                     if exp["name"] == "multirobot-monitoring-15x15"]
    experiment = {**experiment, "policies": ["random", "rl"],
                  "seeds": {"start": 10_000, "count": 1}}
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "c.yaml").write_text(yaml.safe_dump(
        {"name": "outside", "output": "runs", "models": "baselines/agents",
         "experiments": [experiment]}))
    done = subprocess.run([str(bin_folder / "bounce-gym"), "evaluate", "c.yaml", "--no-progress",
                           "--workers", "1"], cwd=outside, capture_output=True, text=True,
                          timeout=600, check=False, env={**clean, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-3000:]
    assert "multirobot-monitoring-15x15: in_region (higher is better); winner:" in done.stdout
    (run,) = (outside / "runs").iterdir()
    with (run / "summary.csv").open() as fh:
        policies = {row["policy"] for row in csv.DictReader(fh)}
    assert {"rl mappo (shared, id)", "rl ippo (shared, id)", "random"} <= policies
