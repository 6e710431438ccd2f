"""Each env family declares its arguments once (a pydantic model); the signatures, the docs
tables, the JSON Schemas and the errors all follow from that declaration."""

from __future__ import annotations

import inspect
import json
import pydoc

import numpy as np
import pytest
from pydantic import ConfigDict, TypeAdapter, ValidationError

import bounce_gym  # noqa: F401 - registers the ids
from bounce_gym.envs import options as bounce_options
from bounce_gym.envs import registration
from bounce_gym.envs.arguments import (
    Accepts,
    arguments_table,
    bare,
    json_schema,
    location,
    registered_env,
    validated,
)
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.drifters import options as drifter_options
from bounce_gym.envs.drifters.env import DrifterEnv
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv
from bounce_gym.envs.goal_navigation_env import GoalNavigationEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv
from bounce_gym.envs.patrol import options as patrol_options
from bounce_gym.envs.patrol.env import PatrolEnv
from bounce_gym.errors import ConfigError

ENV_CLASSES = [BounceEnv, GoalNavigationEnv, MultiBounceEnv, MultiBounceAEC, DrifterEnv,
               MultiDrifterEnv, PatrolEnv]
FAMILIES = [bounce_options, drifter_options, patrol_options]


@pytest.mark.parametrize("cls", ENV_CLASSES, ids=lambda cls: cls.__name__)
def test_the_signature_lists_every_argument_the_env_takes(cls):
    fields = cls.options_model.model_fields
    taken = [name for name in fields if name not in cls.not_taken]
    parameters = inspect.signature(cls).parameters
    keyword_only = [p for p in parameters.values() if p.kind is inspect.Parameter.KEYWORD_ONLY]
    assert [p.name for p in keyword_only] == taken
    for parameter in keyword_only:
        default = cls.option_defaults.get(parameter.name, fields[parameter.name].default)
        assert parameter.default == default, parameter.name
        assert parameter.annotation is not inspect.Parameter.empty
    assert not set(cls.not_taken) & set(parameters)
    assert "render_mode" in parameters


def test_help_shows_the_arguments_with_defaults():
    text = pydoc.render_doc(MultiBounceEnv, renderer=pydoc.plaintext)
    assert "n_robots: int = 4" in text and "history: int = 0" in text
    assert "world: str | os.PathLike" in text


def test_the_envs_own_defaults_replace_the_models():
    assert inspect.signature(MultiBounceEnv).parameters["world"].default == "grid_15x15"
    assert inspect.signature(BounceEnv).parameters["world"].default == "two_rooms"
    assert inspect.signature(GoalNavigationEnv).parameters["task"].default == "goal_navigation"
    assert inspect.signature(DrifterEnv).parameters.get("n_drifters") is None


@pytest.mark.parametrize("family", FAMILIES, ids=lambda module: module.__name__)
def test_every_field_is_described_and_the_schema_is_json(family):
    model = next(value for name, value in vars(family).items()
                 if name.endswith("Options") and hasattr(value, "model_fields"))
    for name, field in model.model_fields.items():
        assert field.description and len(field.description) > 20, name
    schema = json.loads(json.dumps(model.model_json_schema()))
    assert list(schema["properties"]) == list(model.model_fields)
    assert schema["additionalProperties"] is False


@pytest.mark.parametrize(("model", "values"), [
    (bounce_options.EnvOptions, {}),
    (bounce_options.EnvOptions, {"n_robots": 3, "angles": [[30, 60], [90], [120, 150, 170]],
                                 "backend": "pymunk", "noise": {"type": "reliable", "r": 0.8,
                                                                "eps_deg": 5},
                                 "turn_angles": [90]}),
    (patrol_options.PatrolOptions, {"start": [0, 1, 2]}),
    (drifter_options.DrifterOptions, {}),
], ids=["bounce-defaults", "bounce-per-robot", "patrol", "drifter-defaults"])
def test_a_field_holds_its_annotated_type_and_accepts_what_the_signature_shows(model, values):
    """The annotation is the type of the normalised value the envs read (what mypy checks);
    the input type (`Accepts`) is what signatures, tables and the JSON Schema show."""
    options = validated(model, values)
    check = ConfigDict(arbitrary_types_allowed=True, strict=True)
    accepting = {name: item.input_type for name, field in model.model_fields.items()
                 for item in field.metadata if isinstance(item, Accepts)}
    assert {"world", "flow"} & accepting.keys()
    for name, field in model.model_fields.items():
        TypeAdapter(field.annotation, config=check).validate_python(getattr(options, name))
    cls = {bounce_options.EnvOptions: MultiBounceEnv, patrol_options.PatrolOptions: PatrolEnv,
           drifter_options.DrifterOptions: DrifterEnv}[model]
    parameters = inspect.signature(cls).parameters
    for name, input_type in accepting.items():
        if name in parameters:
            assert parameters[name].annotation == bare(input_type), name
            assert parameters[name].annotation != model.model_fields[name].annotation, name


@pytest.mark.parametrize("cls", ENV_CLASSES, ids=lambda cls: cls.__name__)
def test_the_env_schema_and_docs_table_hold_what_it_takes(cls):
    schema = json_schema(cls)
    table = arguments_table(cls)
    names = [name for name in cls.options_model.model_fields if name not in cls.not_taken]
    assert list(schema["properties"]) == names
    assert [row.split("`")[1] for row in table[2:]] == names
    for name, value in cls.option_defaults.items():
        if name in names:
            assert schema["properties"][name]["default"] == value


@pytest.mark.parametrize(("cls", "kwargs", "message"), [
    (BounceEnv, {"history": True}, r"^history: expected an integer in \[0, 10000\], got True$"),
    (BounceEnv, {"step_length": "1"}, r"^step_length: expected a number > 0, got '1'$"),
    (BounceEnv, {"step_mode": 3}, r"^step_mode: expected one of \['bounce', 'tick'\], got 3$"),
    (BounceEnv, {"privileged": "yes"}, r"^privileged: expected True or False, got 'yes'$"),
    (BounceEnv, {"angles": [45, "x"]}, r"^angles\[1\]: expected a number, got 'x'$"),
    (BounceEnv, {"physics_params": {"friction": -1}, "backend": "pymunk"},
     r"^physics_params\.friction: expected a number >= 0"),
    (MultiBounceEnv, {"n_robots": 2, "angles": {"robot_0": [45]}}, r"^angles: dict keys"),
    (DrifterEnv, {"rho": float("nan")}, r"^rho: expected a finite number, got nan$"),
    (DrifterEnv, {"rho": 0}, r"^rho: expected a number in \(0, 1\], got 0$"),
    (DrifterEnv, {"reward": "thesis", "task": "cover"}, r"^reward: only the reach task"),
    (MultiDrifterEnv, {"n_drifters": 0}, r"^n_drifters: expected an integer in \[1, 10000\]"),
    (PatrolEnv, {"cell_size": -1.0}, r"^cell_size: expected a number > 0, got -1.0$"),
    (PatrolEnv, {"n_patrollers": 0}, r"^n_patrollers: expected an integer >= 1, got 0$"),
    (PatrolEnv, {"max_cycles": 10}, r"^attack_time: expected an integer in \[1, 10\], got 20$"),
])
def test_bad_values_are_one_line_config_errors_naming_the_field(cls, kwargs, message):
    with pytest.raises(ConfigError, match=message) as caught:
        cls(**kwargs)
    assert not isinstance(caught.value, ValidationError)
    assert "\n" not in str(caught.value)


def test_numpy_scalars_are_numbers_and_flags():
    env = BounceEnv(history=np.int64(3), step_length=np.float32(0.5), privileged=np.bool_(True))
    assert (env.options.history, env.options.step_length, env.options.privileged) == (3, 0.5, True)
    assert type(env.options.history) is int


@pytest.mark.parametrize("cls", ENV_CLASSES, ids=lambda cls: cls.__name__)
def test_an_unknown_argument_is_a_type_error_with_a_suggestion(cls):
    name = cls.taken()[-1]
    with pytest.raises(TypeError, match=rf"^{cls.__name__}\(\) got an unexpected keyword "
                                        rf"argument '{name}x' \(did you mean '{name}'\?\)$"):
        cls(**{name + "x": 1})


def test_nested_locations_read_as_python():
    assert location(("angles", 2)) == "angles[2]"
    assert location(("physics_params", "friction")) == "physics_params.friction"
    assert location(("angles", 0, 1)) == "angles[0][1]"


@pytest.mark.parametrize("env_id", [*registration.GYMNASIUM_IDS, *registration.PETTINGZOO_ENVS,
                                    *registration.DRIFTER_PETTINGZOO_ENVS,
                                    *registration.PATROL_PETTINGZOO_ENVS])
def test_a_registered_ids_schema_takes_its_registered_arguments(env_id):
    jsonschema = pytest.importorskip("jsonschema")
    schema = json_schema(env_id)
    cls, registered = registered_env(env_id)
    assert list(schema["properties"]) == cls.taken()
    registered = json.loads(json.dumps(registered))  # as a YAML/JSON config holds them
    jsonschema.validate(registered, schema)
    for name, value in registered.items():
        assert schema["properties"][name]["default"] == value
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"colour": 1}, schema)


def test_only_this_packages_ids_have_an_argument_schema():
    with pytest.raises(ConfigError, match="not one of bounce_gym's environments"):
        json_schema("CartPole-v1")
