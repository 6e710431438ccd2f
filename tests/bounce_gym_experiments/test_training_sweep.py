"""Training sweeps (`bounce_gym_experiments.training`): one unit per seed on the in-process executor, the
local pool and a local Ray instance give the same weights bit for bit; a sweep killed after one
seed finished, started again with ``--resume``, skips that seed, continues the other from its
checkpoint and ends with the weights of the sweep never interrupted; a seed that fails is
reported while the others are saved."""

import io
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
import torch
import yaml

pytest.importorskip("stable_baselines3")

from baselines.rl.model_files import read_model  # noqa: E402

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import train  # noqa: E402

CONFIG = {"name": "nav", "env": "bounce_gym/BounceNavigation-v0",
          "env_kwargs": {"world": "square", "backend": "cell", "angles": [90, 135]},
          "algo": "ppo", "total_timesteps": 1024, "seeds": [0, 1], "n_envs": 2,
          "checkpoint_every": 256, "hyperparams": {"n_steps": 64, "batch_size": 64,
                                                   "n_epochs": 1}}


def _write(folder: Path, **changes) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "t.yaml"
    path.write_text(yaml.safe_dump({**CONFIG, "models": str(folder / "models"), **changes}),
                    encoding="utf-8")
    return path


def _weights(path: Path) -> dict:
    with zipfile.ZipFile(io.BytesIO(read_model(path).data)) as archive:
        return torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True)


def _same_weights(a: Path, b: Path) -> bool:
    wa, wb = _weights(a), _weights(b)
    return wa.keys() == wb.keys() and all(torch.equal(wa[k], wb[k]) for k in wa)


def _models(folder: Path) -> list[Path]:
    return [folder / "models" / "nav" / f"ppo_seed{s}.zip" for s in CONFIG["seeds"]]


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The sweep in this process (``--workers 1``, training as it always ran)."""
    folder = tmp_path_factory.mktemp("reference")
    assert train.main([str(_write(folder)), "--workers", "1", "--no-progress"]) == 0
    return folder


@pytest.mark.parametrize("flags", [["--workers", "2"], ["--executor", "ray", "--workers", "2"]],
                         ids=["pool", "ray"])
def test_every_executor_trains_the_same_weights(tmp_path, reference, flags, capsys):
    if "ray" in flags:
        pytest.importorskip("ray")
    assert train.main([str(_write(tmp_path)), *flags, "--no-progress"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == ["ppo_seed0: training 1024 steps", "ppo_seed1: training 1024 steps"]
    for ours, theirs in zip(_models(tmp_path), _models(reference), strict=True):
        assert _same_weights(ours, theirs)
        assert ours.with_name(f"{ours.stem}.monitor.csv").is_file()


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_a_sweep_killed_after_one_seed_resumes_to_the_same_weights(tmp_path, reference):
    config = _write(tmp_path)
    cut = subprocess.Popen([sys.executable, "train.py", str(config), "--workers", "1",
                            "--no-progress"], cwd=ROOT, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True)
    first, second = _models(tmp_path)
    checkpoints = first.parent / "checkpoints"
    while cut.poll() is None and not (first.is_file() and
                                      list(checkpoints.glob("ppo_seed1_*_steps.zip"))):
        time.sleep(0.01)
    os.kill(cut.pid, signal.SIGKILL)
    cut.wait(timeout=60)
    assert first.is_file() and not second.exists(), "killed too late: the sweep had finished"
    done = subprocess.run([sys.executable, "train.py", str(config), "--workers", "2", "--resume",
                           "--no-progress"], cwd=ROOT, capture_output=True, text=True,
                          timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    assert "ppo_seed0: already trained for 1024 steps" in done.stdout
    assert "ppo_seed1: resumed from" in done.stdout
    for ours, theirs in zip(_models(tmp_path), _models(reference), strict=True):
        assert _same_weights(ours, theirs)


def test_a_failing_seed_is_reported_and_the_others_are_saved(tmp_path, capsys, monkeypatch):
    import bounce_gym_experiments.training

    def failing(config, seed, **kwargs):
        if seed == 1:
            raise RuntimeError("no memory left")
        return train_seed(config, seed, **kwargs)

    from baselines.rl.train import train_seed

    monkeypatch.setattr(bounce_gym_experiments.training, "train_seed", failing)
    code = train.main([str(_write(tmp_path)), "--workers", "1", "--no-progress"])
    captured = capsys.readouterr()
    assert code == 1
    assert f"saved {_models(tmp_path)[0]}" in captured.out.splitlines()
    assert captured.err.splitlines() == [
        "error: ppo_seed1 failed after 3 attempts: RuntimeError: no memory left"]


def test_the_executor_key_and_flags_are_checked_before_training(tmp_path, capsys):
    config = _write(tmp_path, executor={"kind": "local", "workers": 0})
    assert train.main([str(config), "--no-progress"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "error: config.executor.workers: expected an integer in [1, 1024], got 0"]
    assert train.main([str(_write(tmp_path)), "--workers", "0", "--no-progress"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "error: --workers: expected an integer in [1, 1024], got 0"]
    assert not (tmp_path / "models").exists()
