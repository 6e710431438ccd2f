"""The generated "Configuration reference" page of the docs site: one table per configuration
model (`bounce_gym_experiments.schema.MODELS` and the models they nest), every key with its
type, default, range and description read from the model, so the page cannot drift from what
``bounce-gym`` accepts."""

from __future__ import annotations

import json

from pydantic import BaseModel

PAGE = "configuration.md"

INTRO = """# Configuration reference

Every key of the evaluation configuration (`bounce-gym evaluate config.yaml`, `evaluate.py`)
and of the training configuration (`bounce-gym train config.yaml`, `train.py`), generated from
the models that check them (`bounce_gym_experiments.config`, `baselines.rl.train_config`).
A key is optional unless its default says *required*. Rules across keys — the seeds' range,
the horizon, which policies a family runs — are in [Evaluation](evaluation.md) and
[Training agents](agents.md).

**Editors.** The same models give the JSON Schemas shipped in `configs/schema/`
(`evaluation.schema.json`, `training.schema.json`; `bounce-gym schema --write` regenerates
them). A configuration whose first line is

```yaml
# yaml-language-server: $schema=schema/evaluation.schema.json
```

(the path relative to the file; `training.schema.json` for a training configuration) is
completed and checked as you type by editors that run the YAML language server, such as VS Code
with its YAML extension; every configuration in `configs/` starts with that line.
"""


def _type(prop: dict, defs: dict) -> str:
    """A field's JSON Schema as a short type text, models linked to their tables."""
    if "$ref" in prop:
        name = prop["$ref"].rsplit("/", 1)[1]
        return f"[{name}](#{name.lower()})"
    if "anyOf" in prop:
        kinds = [_type(p, defs) for p in prop["anyOf"] if p.get("type") != "null"]
        return " or ".join(kinds)
    if "enum" in prop:
        return "one of " + ", ".join(f"`{json.dumps(v)}`" for v in prop["enum"])
    kind = prop.get("type", "any")
    if kind == "array":
        return f"list of {_type(prop.get('items', {}), defs)}"
    return {"object": "mapping", "integer": "integer", "number": "number", "string": "string",
            "boolean": "true or false"}.get(kind, kind)


def _range(prop: dict) -> str:
    members = [prop, *prop.get("anyOf", [])]
    parts = []
    for member in members:
        for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                          ("exclusiveMaximum", "<")):
            if key in member:
                parts.append(f"{sign} {member[key]}")
        if "minItems" in member:
            parts.append(f"at least {member['minItems']} item(s)")
    return ", ".join(parts)


def _default(model: type[BaseModel], key: str) -> str:
    field = model.model_fields[key]
    if field.is_required():
        return "*required*"
    value = field.get_default(call_default_factory=True)
    return "—" if value is None else f"`{json.dumps(value)}`"


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|").replace("<", "&lt;")


def model_table(model: type[BaseModel], schema: dict) -> str:
    """The Markdown table of one model's keys."""
    defs = schema.get("$defs", {})
    own = defs.get(model.__name__, schema)
    rows = ["| Key | Type | Default | Range | Description |", "|---|---|---|---|---|"]
    for key, prop in own["properties"].items():
        if "enum" not in prop and "enum" in (model.model_fields[key].json_schema_extra or {}):
            prop = {**prop, "enum": model.model_fields[key].json_schema_extra["enum"]}
        rows.append(f"| `{key}` | {_cell(_type(prop, defs))} | {_cell(_default(model, key))} | "
                    f"{_cell(_range(prop))} | {_cell(prop.get('description', ''))} |")
    return "\n".join(rows)


def _nested(model: type[BaseModel]) -> list[type[BaseModel]]:
    """``model`` and the models its fields nest, each once, in the order met."""
    out = [model]
    for item in out:
        for field in item.model_fields.values():
            for kind in _members(field.annotation):
                if kind not in out:
                    out.append(kind)
    return out


def _members(annotation: object) -> list[type[BaseModel]]:
    from typing import get_args

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [kind for arg in get_args(annotation) for kind in _members(arg)]


def config_pages() -> dict[str, str]:
    """Page path -> Markdown: the configuration reference."""
    from bounce_gym_experiments.schema import MODELS, schema

    parts = [INTRO]
    titles = {"evaluation": "Evaluation configuration", "training": "Training configuration"}
    for name, root in MODELS.items():
        document = schema(name)
        parts.append(f"## {titles[name]}\n\nSchema: `configs/schema/{name}.schema.json`.\n")
        for model in _nested(root):
            parts.append(f"### {model.__name__}\n\n{_cell(model.__doc__ or '')}\n\n"
                         f"{model_table(model, document)}\n")
    return {PAGE: "\n".join(parts)}
