"""The configuration files' JSON Schemas: the shipped files are the ones the models generate,
every shipped configuration names its schema on its first line and passes both the schema
(`jsonschema`) and the models, and a mistake the schema can see is refused by it."""

import json
import sys
from pathlib import Path

import jsonschema
import pytest

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

from baselines.rl.train_config import validate_train_config  # noqa: E402
from bounce_gym.documents import read_document  # noqa: E402
from bounce_gym_experiments.cli import main  # noqa: E402
from bounce_gym_experiments.config import load_config, validate_config  # noqa: E402
from bounce_gym_experiments.schema import (  # noqa: E402
    MODELS,
    schema,
    schema_folder,
    schema_text,
    write_schemas,
)

CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))


def _kind(path: Path) -> str:
    return "training" if path.name.startswith("train_") else "evaluation"


def _validator(name: str, env_options: dict | None = None) -> jsonschema.Draft202012Validator:
    document = schema(name, env_options)
    jsonschema.Draft202012Validator.check_schema(document)
    return jsonschema.Draft202012Validator(document)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_the_shipped_schema_is_the_generated_one(name):
    shipped = schema_folder() / f"{name}.schema.json"
    assert shipped.read_text(encoding="utf-8") == schema_text(name), (
        f"{shipped} is stale: run bounce-gym schema --write")


def test_the_schema_command_prints_and_writes_the_schemas(tmp_path, capsys, monkeypatch):
    assert main(["schema", "training"]) == 0
    assert capsys.readouterr().out == schema_text("training")
    written = write_schemas(tmp_path)
    assert [p.name for p in written] == ["evaluation.schema.json", "training.schema.json"]
    assert all(json.loads(p.read_text(encoding="utf-8")) == schema(p.name.split(".")[0])
               for p in written)
    assert main(["schema"]) == 2
    assert capsys.readouterr().err.startswith("error: schema: give a configuration")


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_every_shipped_configuration_passes_its_schema_and_its_model(path):
    first = path.read_text(encoding="utf-8").splitlines()[0]
    assert first == f"# yaml-language-server: $schema=schema/{_kind(path)}.schema.json"
    assert (path.parent / "schema" / f"{_kind(path)}.schema.json").is_file()
    document = read_document(path, "config")
    errors = list(_validator(_kind(path)).iter_errors(document))
    assert not errors, [e.message for e in errors]
    if _kind(path) == "training":
        validate_train_config(document, folder=path.parent)
    else:
        validate_config(load_config(path))


@pytest.mark.parametrize(("name", "document", "where"), [
    ("evaluation", {"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0", "sed": 1}]},
     "sed"),
    ("evaluation", {"experiments": [{"name": "a", "env": "bounce_gym/Nope-v0"}]}, "Nope"),
    ("evaluation", {"experiments": []}, "[]"),
    ("evaluation", {"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0",
                                     "seeds": {"start": 5, "count": 1}}]}, "5"),
    ("evaluation", {"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0",
                                     "difficulty": "nightmare"}]}, "nightmare"),
    ("evaluation", {"executor": {"kind": "slurm"}, "experiments": [
        {"name": "a", "env": "bounce_gym/Bounce-v0"}]}, "slurm"),
    ("training", {"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "ppo",
                  "n_envs": 0}, "0"),
    ("training", {"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "a2c"}, "a2c"),
    ("training", {"name": "a", "env": "bounce_gym/Bounce-v0"}, "algo"),
])
def test_the_schema_refuses_what_it_can_see(name, document, where):
    errors = list(_validator(name).iter_errors(document))
    assert errors and any(where in e.message for e in errors), [e.message for e in errors]


def test_env_option_schemas_plug_into_env_kwargs_per_env_id():
    options = {"type": "object", "properties": {"world": {"type": "string"}},
               "additionalProperties": False}
    validator = _validator("evaluation", {"bounce_gym/Bounce-v0": options})
    bad = {"experiments": [{"name": "a", "env": "bounce_gym/Bounce-v0",
                            "env_kwargs": {"colour": 1}}]}
    assert any("colour" in e.message for e in validator.iter_errors(bad))
    other = {"experiments": [{"name": "a", "env": "bounce_gym/BounceCoverage-v0",
                              "env_kwargs": {"colour": 1}}]}
    assert not list(validator.iter_errors(other))
    train = _validator("training", {"bounce_gym/Bounce-v0": options})
    assert list(train.iter_errors({"name": "a", "env": "bounce_gym/Bounce-v0", "algo": "ppo",
                                   "env_kwargs": {"world": 3}}))


@pytest.mark.parametrize(("env_id", "env_kwargs", "word"), [
    ("bounce_gym/BounceNavigation-v0", {"worlds": "two_rooms"}, "worlds"),
    ("bounce_gym/BounceNavigation-v0", {"backend": "physx"}, "physx"),
    ("bounce_gym/MultiBounceCoverage-v0", {"n_robots": 0}, "0"),
    ("bounce_gym/Drifter-v0", {"rho": "high"}, "high"),
    ("bounce_gym/Patrol-v0", {"n_patrollers": "two"}, "two"),
])
def test_the_shipped_schema_checks_each_envs_own_arguments(env_id, env_kwargs, word):
    shipped = json.loads((ROOT / "configs" / "schema" / "evaluation.schema.json").read_text())
    validator = jsonschema.Draft202012Validator(shipped)
    good = {"experiments": [{"name": "a", "env": env_id}]}
    assert not list(validator.iter_errors(good))
    bad = {"experiments": [{"name": "a", "env": env_id, "env_kwargs": env_kwargs}]}
    messages = [e.message for e in validator.iter_errors(bad)]
    assert any(word in message for message in messages), messages
