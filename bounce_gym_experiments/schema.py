"""The JSON Schemas of the configuration files, generated from their models: the evaluation
configuration (`bounce_gym_experiments.config.EvaluationConfig`) and the training configuration
(`baselines.rl.train_config.TrainingConfig`).

They ship as ``configs/schema/<name>.schema.json`` (installed with
``bounce_gym_experiments.configs``), so that an editor completes and checks a configuration file
whose first line is ``# yaml-language-server: $schema=schema/<name>.schema.json`` (VS Code's
YAML extension, any editor with the YAML language server). ``bounce-gym schema --write``
regenerates them; a test keeps the shipped files equal to the generated ones. The schema checks
what can be checked without the package (keys, types, ranges, choices); the rules across keys
(the seeds' range, the horizon, a family's policies) are checked by ``bounce-gym`` itself.

The env options (``env_kwargs``) are an open object with a description, unless
`env_options_schemas` gives an env id's own schema: the one place where the envs' option
schemas are plugged in.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

from baselines.rl.train_config import TrainingConfig
from bounce_gym.files import atomic_write
from bounce_gym_experiments.config import EvaluationConfig, configs_folder

#: the configuration files' models, by the name of their schema
MODELS = {"evaluation": EvaluationConfig, "training": TrainingConfig}
#: the JSON Schema dialect of the generated schemas (pydantic's)
DIALECT = "https://json-schema.org/draft/2020-12/schema"


def env_options_schemas() -> dict[str, dict]:
    """The JSON Schema of each env id's options (``env_kwargs``), by id: where the envs'
    option schemas are plugged in. None yet: every ``env_kwargs`` is an open object."""
    return {}


def schema_folder() -> Path:
    """Where the schemas ship: ``schema/`` of the shipped configurations."""
    return configs_folder() / "schema"


def schema(name: str, env_options: Mapping[str, dict] | None = None) -> dict:
    """The JSON Schema of configuration ``name`` (of `MODELS`), with the env options of
    ``env_options`` (default: `env_options_schemas`) as ``env_kwargs`` for their env ids."""
    model = MODELS[name]
    out = {"$schema": DIALECT, **model.model_json_schema()}
    env_options = env_options_schemas() if env_options is None else env_options
    if env_options:
        target = out["$defs"]["Experiment"] if name == "evaluation" else out
        target["allOf"] = [
            {"if": {"properties": {"env": {"const": env_id}}, "required": ["env"]},
             "then": {"properties": {"env_kwargs": options}}}
            for env_id, options in sorted(env_options.items())]
    return out


def schema_text(name: str) -> str:
    """The file text of schema ``name``: indented JSON, keys in a fixed order."""
    return json.dumps(schema(name), indent=2, ensure_ascii=False) + "\n"


def write_schemas(folder: Path | None = None) -> list[Path]:
    """Write every schema into ``folder`` (default: `schema_folder`); the paths written."""
    folder = schema_folder() if folder is None else folder
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name in MODELS:
        path = folder / f"{name}.schema.json"
        atomic_write(path, schema_text(name).encode("utf-8"))
        written.append(path)
    return written
