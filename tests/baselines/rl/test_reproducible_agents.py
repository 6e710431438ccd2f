"""What is reproducible about the shipped agents, and where (docs/learning.md, "Reproducible
agents"): the navigation-lab-v1 folder holds one agent of every learner kind (SB3 PPO, SB3 DQN
with hindsight relabelling, jax_ppo, jax_dqn).

* **Weights, on one machine.** Each kind is retrained from its training configuration in
  ``configs/``, with the budget capped (``BOUNCE_GYM_MAX_TIMESTEPS``, past DQN's
  ``learning_starts`` so that gradient steps happen), twice, in two separate processes: the two
  runs' weights must be equal bit for bit.
* **Scores, across machines.** Torch and XLA may pick other vectorised kernels on another CPU,
  so the shipped weights are not expected back there; what must hold anywhere is their score.
  Every shipped agent plays held-out episodes (seeds 10000 on), and the Wilson 95% interval of
  its success, and of its kind's five seeds pooled, must overlap the interval of the kind's row
  in the recorded results (the benchmark's leaderboard, docs/results/benchmark).
"""

from __future__ import annotations

import csv
import io
import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("jax")
pytest.importorskip("optax")
pytest.importorskip("stable_baselines3")

import gymnasium as gym  # noqa: E402

import bounce_gym  # noqa: E402,F401
from baselines.rl.model_files import WEIGHTS_ENTRY, read_model  # noqa: E402
from bounce_gym_experiments.stats import wilson_interval  # noqa: E402

ROOT = Path(__file__).parents[3]
CONFIGS = ROOT / "configs"
FOLDER = ROOT / "baselines" / "agents" / "navigation-lab-v1"
#: the configuration training each kind of the folder (test_shipped_agents checks the pairing)
KINDS = {"ppo": "train_navigation_v1_ppo.yaml", "dqn": "train_navigation_her.yaml",
         "jax_ppo": "train_navigation_v1_jax_ppo.yaml",
         "jax_dqn": "train_navigation_v1_jax_dqn.yaml"}
#: env steps per retrain: past DQN's learning_starts (2000), three PPO iterations (3 x 1024)
CAP = 2400
#: held-out episodes per shipped agent
EPISODES = 40
FIRST_SEED = 10_000
#: the recorded results: the benchmark's leaderboard (docs/results/benchmark), whose rows of
#: navigation-lab-v1 docs/jax.md shows
RECORDED = ROOT / "docs" / "results" / "benchmark" / "leaderboard.csv"
ROW = re.compile(r"rl (\w+) \(pose observed\)")

RETRAIN = """
import sys
from pathlib import Path

from baselines.rl.train import train
from bounce_gym.documents import read_document
from bounce_gym_experiments.cli import training_config

out, configs = Path(sys.argv[1]), Path(sys.argv[2])
for name in sys.argv[3:]:
    config = training_config(read_document(configs / name), seeds=[0])  # the budget cap applies
    config["models"] = str(out)
    (path,) = train(config, progress=False, folder=configs)
    print(path)
"""


def _retrain(out: Path) -> None:
    """Every kind's seed 0 retrained into ``out``, in a process of its own."""
    env = {**os.environ, "BOUNCE_GYM_MAX_TIMESTEPS": str(CAP), "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", RETRAIN, str(out), str(CONFIGS),
                           *KINDS.values()], cwd=out.parent, env=env, capture_output=True,
                          text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]


def _weights(path: Path) -> dict[str, np.ndarray]:
    """The named weight arrays of a model file: a JAX learner's ``.npz``, an SB3 policy's
    state dict (read as tensors only)."""
    trained = read_model(path)
    with zipfile.ZipFile(io.BytesIO(trained.data)) as archive:
        if trained.algo.startswith("jax_"):
            with np.load(io.BytesIO(archive.read(WEIGHTS_ENTRY)), allow_pickle=False) as npz:
                return {name: npz[name] for name in npz.files}
        import torch

        state = torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True)
        return {name: tensor.numpy() for name, tensor in state.items()}


def _differences(a: Path, b: Path) -> dict[str, float]:
    """The largest absolute difference of each weight array that is not bit-identical (arrays
    compared byte for byte, so a NaN or a signed zero counts)."""
    wa, wb = _weights(a), _weights(b)
    assert wa.keys() == wb.keys() and wa, f"{a.name}: other weight names"
    out = {}
    for name in wa:
        x, y = wa[name], wb[name]
        if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
            out[name] = float(np.max(np.abs(x.astype(np.float64) - y.astype(np.float64))))
    return out


@pytest.mark.slow  # four retrains twice, ~1 min
@pytest.mark.long
def test_retraining_each_kind_twice_on_one_machine_gives_the_same_weights(tmp_path):
    _retrain(tmp_path / "a")
    _retrain(tmp_path / "b")
    for algo in KINDS:
        a = tmp_path / "a" / "navigation-lab-v1" / f"{algo}_seed0.zip"
        b = tmp_path / "b" / a.relative_to(tmp_path / "a")
        trained = read_model(a)
        config = trained.metadata["config"]
        assert trained.algo == algo and config["total_timesteps"] == CAP
        assert config["hyperparams"].get("learning_starts", 0) < CAP  # gradient steps were taken
        assert _differences(a, b) == {}, f"{algo}: retrained weights differ"
        made = trained.trained_with()  # the record of the machine that trained them
        assert made == read_model(b).trained_with() and made["machine"]
        # not the shipped file compared with itself: the short retrain ends elsewhere
        assert _differences(a, FOLDER / a.name), f"{algo}: equal to the shipped weights"


def _success(path: Path) -> int:
    """Successes of the shipped agent at ``path`` over `EPISODES` held-out episodes, played as
    the evaluation plays them (sampled actions, drawn from each episode's seed)."""
    from baselines.rl.jaxrl.policy import JaxPolicy
    from baselines.rl.policies import SB3Policy
    from bounce_gym_experiments.runner import run_episode

    env = gym.make("bounce_gym/BounceNavigation-v1")
    policy = (JaxPolicy if path.name.startswith("jax_") else SB3Policy)(path, env)
    reached = sum(bool(run_episode(env, policy, seed, env.spec.max_episode_steps)[0]["info"][
        "is_success"]) for seed in range(FIRST_SEED, FIRST_SEED + EPISODES))
    env.close()
    return reached


def _overlap(a: tuple[float, float], b: tuple[float, float]) -> bool:
    return a[0] <= b[1] and b[0] <= a[1]


@pytest.mark.slow  # 20 agents x 40 episodes, ~15 s
def test_shipped_agents_score_within_the_recorded_results():
    with RECORDED.open(encoding="utf-8") as fh:
        recorded = {ROW.fullmatch(row["policy"])[1]: (float(row["success_lo"]),
                                                       float(row["success_hi"]))
                    for row in csv.DictReader(fh) if row["experiment"] == "navigation-lab-v1"
                    and ROW.fullmatch(row["policy"])}
    assert set(recorded) == set(KINDS), recorded
    for algo, (lo, hi) in recorded.items():
        models = sorted(FOLDER.glob(f"{algo}_seed*.zip"))
        assert len(models) == 5
        successes = {path.name: _success(path) for path in models}
        for name, won in successes.items():
            interval = wilson_interval(won, EPISODES)
            assert _overlap(interval, (lo, hi)), f"{name}: {won}/{EPISODES} {interval} " \
                                                 f"against the recorded [{lo}, {hi}]"
        pooled = wilson_interval(sum(successes.values()), EPISODES * len(models))
        assert _overlap(pooled, (lo, hi)), f"{algo}: {successes} against [{lo}, {hi}]"
