"""The trained agents that come with the package: ``baselines/agents/<folder>/``, one folder per
training configuration's ``name`` (its models, manifest and learning curves), installed with the
wheel as package data.

A configuration names them as ``models: baselines/agents`` (`SHIPPED_MODELS`); in a checkout
that is the folder of the repository, and outside one — where no such folder is below the current
one — the installed package's copy (`models_folder`). Their manifests list every model file's
sha256, so the evaluation reads only the files the package shipped.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["SHIPPED_MODELS", "models_folder", "shipped_agents"]

#: how a configuration names the shipped agents' folder (its ``models`` key)
SHIPPED_MODELS = "baselines/agents"


def shipped_agents() -> Path:
    """The installed package's folder of trained agents."""
    return Path(__file__).parent / "agents"


def models_folder(models: str) -> str:
    """The models folder a configuration's ``models`` names: the path as given (from the current
    folder), except the shipped agents' name where nothing is there, which is the installed
    package's folder (`shipped_agents`)."""
    if Path(models) == Path(SHIPPED_MODELS) and not Path(models).is_dir():
        return str(shipped_agents())
    return models
