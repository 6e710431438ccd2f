"""A training run killed (SIGKILL) at any instant leaves only complete, listed model files,
and the evaluation loads what is there."""

import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import gymnasium as gym
import pytest
import yaml

import bounce_gym  # noqa: F401
from baselines.rl.model_files import MANIFEST, MODEL_NAME, load_model, read_model
from bounce_gym_experiments.runner import run

ROOT = Path(__file__).parents[3]
NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}


def _start(folder: Path) -> subprocess.Popen:
    config = {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
              "algo": "ppo", "total_timesteps": 320, "n_envs": 1, "checkpoint_every": 32,
              "hyperparams": {"n_steps": 32, "batch_size": 32, "n_epochs": 1},
              "models": str(folder / "models")}
    (folder / "t.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    return subprocess.Popen([sys.executable, "-m", "bounce_gym_experiments.cli", "train",
                             str(folder / "t.yaml"), "--no-progress"], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _wait_for_first_checkpoint(proc: subprocess.Popen, folder: Path) -> None:
    checkpoints = folder / "models" / "nav" / "checkpoints"
    while proc.poll() is None and not (checkpoints.is_dir() and any(checkpoints.iterdir())):
        time.sleep(0.005)


@pytest.mark.slow  # ~14 s: training runs killed at many instants
@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_sigkill_at_any_instant_leaves_only_complete_listed_models(tmp_path):
    env = gym.make("bounce_gym/BounceNavigation-v0", **NAV)
    # seconds after the first checkpoint file (its hidden temporary file) appears; None: finish
    delays = [0.0, 0.05, 0.5, None]
    for k, delay in enumerate(delays):
        folder = tmp_path / f"run{k}"
        folder.mkdir()
        proc = _start(folder)
        _wait_for_first_checkpoint(proc, folder)
        if delay is None:
            assert proc.wait(timeout=300) == 0
        else:
            time.sleep(delay)
            if proc.poll() is None:
                os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout=60)
        zips = sorted((folder / "models").rglob("*.zip"))
        assert zips or delay is not None
        for path in zips:
            assert path.stat().st_size > 0, path
            with zipfile.ZipFile(path) as archive:
                assert archive.testzip() is None, path
            # listed in its folder's manifest with this content, and readable
            assert read_model(path).path.name in json.loads((path.parent / MANIFEST).read_text())
            if MODEL_NAME.fullmatch(path.name):
                load_model(path, env.observation_space, env.action_space)
        assert not [p for p in (folder / "models").rglob("*") if p.name.endswith(".zip")
                    and not p.name.startswith(("ppo_seed0", "."))]
    config = {"models": str(tmp_path / f"run{len(delays) - 1}" / "models"),
              "experiments": [{"name": "nav", "env": "bounce_gym/BounceNavigation-v0",
                               "env_kwargs": NAV, "seeds": [10_000], "max_steps": 5,
                               "horizon_reason": "a quick test",
                               "policies": ["rl"]}]}
    rows, _ = run(config, progress=False)
    assert [r.policy for r in rows] == ["rl ppo_seed0", "rl ppo_seed0 (greedy)"]
