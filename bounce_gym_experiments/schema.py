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

The env options (``env_kwargs``) of an experiment or training run are checked against its env
id's own arguments (`env_options_schemas`: `bounce_gym.envs.arguments.json_schema`, the env's
declared options with the id's registered defaults), so an editor completes ``world``,
``backend``, ``angles`` ... for the env the file names.
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Mapping
from pathlib import Path

from pydantic import TypeAdapter

from baselines.rl.train_config import TrainingConfig
from bounce_gym.envs import registration
from bounce_gym.envs.arguments import json_schema, registered_env
from bounce_gym.files import atomic_write
from bounce_gym_experiments.config import EvaluationConfig, configs_folder

#: the configuration files' models, by the name of their schema
MODELS = {"evaluation": EvaluationConfig, "training": TrainingConfig}
#: the JSON Schema dialect of the generated schemas (pydantic's)
DIALECT = "https://json-schema.org/draft/2020-12/schema"


def env_options_schemas() -> dict[str, dict]:
    """The JSON Schema of each registered env id's options (``env_kwargs``), by id."""
    ids = [*registration.GYMNASIUM_IDS, *registration.PETTINGZOO_ENVS,
           *registration.DRIFTER_PETTINGZOO_ENVS, *registration.PATROL_PETTINGZOO_ENVS]
    return {env_id: _with_own_parameters(env_id, json_schema(env_id)) for env_id in ids}


def _with_own_parameters(env_id: str, options: dict) -> dict:
    """``options`` plus the env class's own named parameters but ``render_mode`` (a PettingZoo
    env's ``max_cycles``, ...): keyword arguments of the make call too (training configurations
    may set them; the evaluation configuration refuses a horizon there itself)."""
    cls, _ = registered_env(env_id)
    own = list(inspect.signature(cls.__init__, eval_str=True).parameters.values())[1:]
    extra = {parameter.name: {**TypeAdapter(parameter.annotation).json_schema(),
                              "default": parameter.default}
             for parameter in own if parameter.name != "render_mode"
             and parameter.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD}
    return {**options, "properties": {**extra, **options["properties"]}}


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
        # a training run with a ``role`` (the patrol game's sides) trains in a wrapper env
        # (`baselines.rl.patrol`) whose arguments are the env's and the role's: unchecked here
        plain = {"not": {"required": ["role"]}} if name == "training" else {}
        target["allOf"] = [
            {"if": {"properties": {"env": {"const": env_id}}, "required": ["env"], **plain},
             "then": {"properties": {"env_kwargs": _hoisted(out, env_id, options)}}}
            for env_id, options in sorted(env_options.items())]
    return out


def _hoisted(root: dict, env_id: str, options: dict) -> dict:
    """A reference to ``options`` moved into ``root``'s ``$defs`` with its own definitions (a
    ``$ref`` points into the document's root, so a nested schema's ``$defs`` cannot stay
    nested): ``env_kwargs.<id>`` and ``env_kwargs.<id>.<definition>``."""
    prefix = "env_kwargs." + "".join(c if c.isalnum() or c in "-_" else "_" for c in env_id)
    text = json.dumps(options).replace('"#/$defs/', f'"#/$defs/{prefix}.')
    hoisted = json.loads(text)
    defs = root.setdefault("$defs", {})
    for key, definition in hoisted.pop("$defs", {}).items():
        defs[f"{prefix}.{key}"] = definition
    defs[prefix] = hoisted
    return {"$ref": f"#/$defs/{prefix}"}


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
