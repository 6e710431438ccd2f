"""Training determinism and resuming: same configuration and seed, same weights; a run
interrupted (an exception mid-rollout, or SIGKILL) and resumed reaches the step count, weights
and monitor file of the run never interrupted; nothing to resume, a changed configuration or
existing checkpoints are refused."""

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

from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402

from baselines.rl.model_files import CHECKPOINT_NAME, read_model, save_model  # noqa: E402
from baselines.rl.train import RunFiles, train, validate_train_config  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402

ROOT = Path(__file__).parents[3]
NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}
SMALL = {"n_steps": 32, "batch_size": 32, "n_epochs": 2}
PATROL = {"world": "square", "cell_size": 2.0, "sensor_range": 1.5, "attack_time": 4,
          "max_cycles": 40}
BASE = {"name": "n", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
        "total_timesteps": 640, "checkpoint_every": 128}
CASES = {
    "ppo-native-normalised": dict(algo="ppo", n_envs=2, normalize=True, hyperparams=SMALL),
    "ppo-sync-stacked": dict(algo="ppo", n_envs=2, vec_env="sync", n_stack=3,
                             normalize={"norm_reward": False}, hyperparams=SMALL),
    "recurrentppo": dict(algo="recurrentppo", n_envs=2,
                         hyperparams={**SMALL, "policy_kwargs": {"lstm_hidden_size": 8}}),
    "dqn": dict(algo="dqn", hyperparams={"learning_starts": 50, "buffer_size": 500,
                                         "target_update_interval": 100}),
    "multi-robot": dict(algo="ppo", env="bounce_gym/MultiBounceCoverage-v0",
                        env_kwargs={"world": "grid_10x10", "n_robots": 2, "backend": "cell",
                                    "step_mode": "tick", "max_cycles": 50}, hyperparams=SMALL),
    "patrol-patrollers": dict(algo="ppo", env="bounce_gym/Patrol-v0", role="patrollers",
                              env_kwargs=PATROL, hyperparams=SMALL),
    # the adversary's weights over the targets (PatrollersEnv.respond) resume with the env
    "patrol-patrollers-softmin": dict(algo="ppo", env="bounce_gym/Patrol-v0", role="patrollers",
                                      env_kwargs={**PATROL, "adversary": "softmin"},
                                      hyperparams=SMALL),
    "patrol-adversary": dict(algo="ppo", env="bounce_gym/Patrol-v0", role="adversary", n_envs=2,
                             env_kwargs=PATROL, hyperparams=SMALL),
}


class Interrupt(BaseCallback):
    """Stops training, as Ctrl-C would, once the run has taken ``at`` env steps."""

    def __init__(self, at: int) -> None:
        super().__init__()
        self.at = at

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.at:
            raise KeyboardInterrupt
        return True


def _weights(path: Path) -> dict:
    with zipfile.ZipFile(io.BytesIO(read_model(path).data)) as archive:
        return torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True)


def _same_weights(a: Path, b: Path) -> bool:
    wa, wb = _weights(a), _weights(b)
    return wa.keys() == wb.keys() and all(torch.equal(wa[k], wb[k]) for k in wa)


def _episodes(model: Path) -> list[list[str]]:
    """The monitor rows without the wall-clock column."""
    monitor = model.with_name(model.name.replace(".zip", ".monitor.csv"))
    return [row.split(",")[:2] + row.split(",")[3:]
            for row in monitor.read_text().splitlines()[2:]]


def _checkpoint_steps(model: Path) -> int:
    """The step count of the newest checkpoint of the run whose model is ``model``."""
    stem = model.name.removesuffix(".zip")
    names = [CHECKPOINT_NAME.fullmatch(p.name) for p in (model.parent / "checkpoints").iterdir()
             if p.name.startswith(f"{stem}_")]
    return max(int(m.group("steps")) for m in names if m)


def _spaces(config: dict) -> tuple:
    import gymnasium as gym

    env = gym.make(config["env"], **config["env_kwargs"])
    return env.observation_space, env.action_space


def test_same_configuration_and_seed_give_the_same_weights(tmp_path):
    config = {**BASE, **CASES["ppo-native-normalised"]}
    (a,) = train({**config, "models": str(tmp_path / "a")}, progress=False)
    (b,) = train({**config, "models": str(tmp_path / "b")}, progress=False)
    (c,) = train({**config, "models": str(tmp_path / "c"), "seed": 1}, progress=False)
    assert _same_weights(a, b) and _episodes(a) == _episodes(b)
    assert not _same_weights(a, c)
    made = read_model(a).trained_with()  # the machine and libraries, in the metadata
    assert made == read_model(b).trained_with() == read_model(a).metadata["trained_with"]
    assert made["packages"]["torch"] == torch.__version__ and made["python"].count(".") == 2


@pytest.mark.parametrize("case", list(CASES))
def test_an_interrupted_run_resumes_to_the_uninterrupted_one(tmp_path, case):
    config = {**BASE, **CASES[case]}
    (whole,) = train({**config, "models": str(tmp_path / "whole")}, progress=False)
    cut = {**config, "models": str(tmp_path / "cut")}
    with pytest.raises(KeyboardInterrupt):
        train(cut, progress=False, callbacks=[Interrupt(400)])
    folder = tmp_path / "cut" / "n"
    before = {p.name: p.read_bytes() for p in (folder / "checkpoints").glob("*.zip")}
    assert sorted(int(CHECKPOINT_NAME.fullmatch(n).group("steps")) for n in before)[-1] < 400
    assert not list(folder.glob("*_seed0.zip"))  # no final model yet
    (resumed,) = train({**cut, "resume": True}, progress=False)
    assert _checkpoint_steps(resumed) == _checkpoint_steps(whole)
    assert _same_weights(resumed, whole)
    assert _episodes(resumed) == _episodes(whole)  # each episode once, none replayed
    after = {p.name: p.read_bytes() for p in (folder / "checkpoints").glob("*.zip")}
    assert all(after[name] == data for name, data in before.items())  # none overwritten
    assert sorted(after) == sorted(p.name for p in (whole.parent / "checkpoints").glob("*.zip"))


def test_a_finished_run_resumed_with_a_larger_budget_trains_on(tmp_path):
    config = {**BASE, **CASES["ppo-native-normalised"], "checkpoint_every": 0}
    (whole,) = train({**config, "models": str(tmp_path / "whole")}, progress=False)
    short = {**config, "models": str(tmp_path / "short"), "total_timesteps": 320}
    train(short, progress=False)
    (longer,) = train({**short, "total_timesteps": 640, "resume": True}, progress=False)
    assert _checkpoint_steps(longer) == _checkpoint_steps(whole) == 640
    assert _same_weights(longer, whole) and _episodes(longer) == _episodes(whole)


def _cli(folder: Path, *extra: str) -> subprocess.Popen:
    folder.mkdir(exist_ok=True)
    config = {**BASE, **CASES["ppo-native-normalised"], "models": str(folder / "models"),
              "total_timesteps": 1024, "checkpoint_every": 128}
    (folder / "t.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    return subprocess.Popen([sys.executable, "train.py", str(folder / "t.yaml"), "--no-progress",
                             *extra], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


@pytest.mark.slow  # ~13 s: a reference run, a killed run and its resume
@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_a_killed_run_resumes_from_its_newest_checkpoint_to_the_same_weights(tmp_path):
    whole = _cli(tmp_path / "whole")
    assert whole.wait(timeout=300) == 0, whole.stderr.read()
    cut = _cli(tmp_path / "cut")
    checkpoints = tmp_path / "cut" / "models" / "n" / "checkpoints"
    while cut.poll() is None and len(list(checkpoints.glob("*.zip"))) < 2:
        time.sleep(0.01)
    os.kill(cut.pid, signal.SIGKILL)
    cut.wait(timeout=60)
    assert not (tmp_path / "cut" / "models" / "n" / "ppo_seed0.zip").exists(), \
        "the run finished before it was killed"
    resumed = _cli(tmp_path / "cut", "--resume")
    out, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    assert "ppo_seed0: resumed from" in out
    a = tmp_path / "whole" / "models" / "n" / "ppo_seed0.zip"
    b = tmp_path / "cut" / "models" / "n" / "ppo_seed0.zip"
    assert _checkpoint_steps(a) == _checkpoint_steps(b) == 1024
    assert _same_weights(a, b) and _episodes(a) == _episodes(b)


def test_refused_resumes_and_overwrites(tmp_path):
    config = {**BASE, **CASES["ppo-native-normalised"], "models": str(tmp_path),
              "total_timesteps": 64, "checkpoint_every": 0}
    with pytest.raises(ConfigError, match=r"config.resume: nothing to resume: .* holds no "
                                          r"checkpoint of ppo_seed0; train without --resume"):
        train({**config, "resume": True}, progress=False)
    assert not (tmp_path / "n").exists()
    (path,) = train(config, progress=False)
    checkpoint = RunFiles(validate_train_config(config), 0).checkpoint(64)
    data = checkpoint.read_bytes()
    with pytest.raises(ConfigError, match=r"already holds checkpoints of ppo_seed0 \(the newest "
                                          r"at 64 steps\); pass --resume"):
        train(config, progress=False)
    with pytest.raises(ConfigError, match=r"config.n_envs: the checkpoint .* was trained with 2, "
                                          r"this configuration says 3"):
        train({**config, "n_envs": 3, "resume": True, "total_timesteps": 128}, progress=False)
    with pytest.raises(ConfigError, match="a checkpoint is never overwritten"):
        save_model(read_model(checkpoint).load(*_spaces(config)), checkpoint, overwrite=False)
    assert checkpoint.read_bytes() == data
    # seeds without a checkpoint start afresh when others resume
    (p0, p1) = train({**config, "seeds": [0, 1], "resume": True, "total_timesteps": 128},
                     progress=False)
    assert _checkpoint_steps(p1) == 128 and p0.is_file() and p1.is_file()
