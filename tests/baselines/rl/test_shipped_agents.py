"""The reference agents shipped in baselines/agents: data-only model files, each the exact
product of a training configuration in configs/, small enough to ship."""

from __future__ import annotations

from pathlib import Path

import pytest

from baselines.rl.model_files import MODEL_NAME, read_model
from baselines.rl.train import finished, validate_train_config
from bounce_gym.documents import read_document

ROOT = Path(__file__).parents[3]
AGENTS = ROOT / "baselines" / "agents"
CONFIGS = ROOT / "configs"
MODELS = sorted(AGENTS.glob("*/*_seed*.zip"))
#: the most bytes the shipped agents may take together
BUDGET = 30 * 2**20


def _training_configs() -> dict[str, dict]:
    """Every training configuration of configs/, by file name, saving into the agents folder."""
    return {path.name: {**validate_train_config(read_document(path), CONFIGS),
                        "models": str(AGENTS)}
            for path in sorted(CONFIGS.glob("train_*.yaml"))}


def test_agents_are_shipped_within_budget():
    assert len(MODELS) >= 5
    assert sum(path.stat().st_size for path in AGENTS.rglob("*") if path.is_file()) <= BUDGET
    assert not list(AGENTS.glob("*/checkpoints"))


@pytest.mark.parametrize("path", MODELS, ids=[f"{p.parent.name}/{p.name}" for p in MODELS])
def test_each_agent_is_what_its_training_config_trains(path):
    assert MODEL_NAME.fullmatch(path.name)
    trained = read_model(path)  # the folder's manifest vouches for the file
    seed = int(path.stem.rsplit("_seed", 1)[1])
    matches = [name for name, config in _training_configs().items()
               if config["name"] == path.parent.name and config["algo"] == trained.algo
               and seed in config["seeds"] and finished(config, seed)]
    assert len(matches) == 1, f"{path}: reproduced by {matches}"
