"""Constructor arguments declared once, as pydantic models, and what is derived from a model.

Each env family declares its keyword arguments in one model (`bounce_gym.envs.options.EnvOptions`,
`bounce_gym.envs.drifters.options.DrifterOptions`, `bounce_gym.envs.patrol.options.PatrolOptions`):
per field its type, default and description; field and model validators check values and
normalise them. An env class names its model and, where it differs from the model, its own
defaults and the arguments it does not take (`TakesArguments`); from that follow

* `parse`: the env's keyword arguments validated into the model; an unknown keyword is the
  `TypeError` Python raises for one (with "did you mean"), every bad value one `ConfigError`
  "<field>: <what is allowed>, got <value>" (`config_error`: pydantic's `ValidationError` never
  leaves this module);
* `signature`: the class's `inspect.Signature`, so ``help()`` and editors list every argument;
* `arguments_table`: the Markdown table of the docs' env pages;
* `json_schema`: the JSON Schema of the arguments an env class, or a registered id, takes.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import operator
import types
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, Generic, Literal, TypeVar

import numpy as np
from pydantic import (
    AllowInfNan,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    GetCoreSchemaHandler,
    ValidationError,
    ValidationInfo,
)
from pydantic.fields import FieldInfo
from pydantic_core import CoreSchema, to_jsonable_python

from bounce_gym.errors import BounceGymError, ConfigError
from bounce_gym.validate import field_path, unexpected


def _python_scalar(value: object) -> object:
    """A numpy scalar as the Python bool, int or float it holds (the models are strict: they
    take numbers and flags only as such, never a string or a bool for a number)."""
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    return value


#: An integer (Python or numpy; not a bool).
Integer = Annotated[int, BeforeValidator(_python_scalar)]
#: A finite real number (int or float, Python or numpy; not a bool, string or complex).
Real = Annotated[float, BeforeValidator(_python_scalar), AllowInfNan(False)]
#: True or False (numpy bools included).
Flag = Annotated[bool, BeforeValidator(_python_scalar)]


#: JSON Schema's names of the bounds a field declares (pydantic writes a bound that follows a
#: validator, as those of `Integer` and `Real` do, under its own name)
_JSON_BOUNDS = {"ge": "minimum", "le": "maximum", "gt": "exclusiveMinimum",
                "lt": "exclusiveMaximum"}


def _standard_bounds(schema: dict) -> None:
    """Rename the bounds of every (nested) field schema of ``schema`` to JSON Schema's names."""
    for key in [key for key in schema if key in _JSON_BOUNDS]:
        schema[_JSON_BOUNDS[key]] = schema.pop(key)
    for value in schema.values():
        for item in value.values() if isinstance(value, dict) else (
                value if isinstance(value, list) else ()):
            if isinstance(item, dict):
                _standard_bounds(item)


@dataclass(frozen=True)
class Accepts:
    """Field metadata: what a user may pass for a field whose annotation is the type of the
    value validation stores (``world: Annotated[World, Accepts(str | PathLike | World)]``: a
    name or path in, a `World` stored). The input is checked as ``input_type`` (pydantic's type
    and range checks, then the field's validators, which normalise it), and ``input_type`` is
    what the JSON Schema, the signature and the docs' table show."""

    input_type: Any

    def __get_pydantic_core_schema__(self, source: object,
                                     handler: GetCoreSchemaHandler) -> CoreSchema:
        return handler.generate_schema(self.input_type)


def accepted(field: FieldInfo) -> object:
    """The type a field accepts: its `Accepts` input type, else its annotation."""
    for item in field.metadata:
        if isinstance(item, Accepts):
            return item.input_type
    return field.annotation


class Arguments(BaseModel):
    """Base of the argument models: strict types, no unknown fields, every default validated
    (defaults are normalised like given values)."""

    model_config = ConfigDict(strict=True, extra="forbid", arbitrary_types_allowed=True,
                              validate_default=True, frozen=True,
                              json_schema_extra=_standard_bounds)


ModelT = TypeVar("ModelT", bound=Arguments)


class TakesArguments(Generic[ModelT]):
    """Mixin of an env class whose keyword arguments are those of ``options_model`` minus
    ``not_taken`` (they keep the model's default), with ``option_defaults`` replacing some of
    the model's defaults. Every subclass gets a ``__signature__`` derived from them."""

    #: the model (a class attribute; not a ClassVar only because a ClassVar cannot be generic)
    options_model: type[ModelT]
    option_defaults: ClassVar[Mapping[str, object]] = {}
    not_taken: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if hasattr(cls, "options_model"):
            cls.__signature__ = signature(cls)

    @classmethod
    def taken(cls) -> list[str]:
        """The names of the model's arguments this env takes, in declaration order."""
        return [name for name in cls.options_model.model_fields if name not in cls.not_taken]


def needs(info: ValidationInfo, *names: str) -> list:
    """The validated values of the earlier fields ``names`` a field validator depends on. If
    one of them failed, this field fails too, after it: `config_error` reports the first."""
    missing = [name for name in names if name not in info.data]
    if missing:
        raise ValueError(f"depends on {missing[0]}, which is not valid")
    return [info.data[name] for name in names]


def parse(cls: type[TakesArguments[ModelT]], kwargs: Mapping[str, object],
          defaults: Mapping[str, object] | None = None) -> ModelT:
    """``kwargs`` of an env of class ``cls`` validated into its model (``defaults``: values
    that replace the class's defaults for this one call)."""
    taken = cls.taken()
    for name in kwargs:
        if name not in taken:
            raise unexpected(cls.__name__, name, taken)
    return validated(cls.options_model, {**cls.option_defaults, **(defaults or {}), **kwargs})


def validated(model: type[ModelT], values: Mapping[str, object]) -> ModelT:
    """``values`` validated into ``model``; a bad one is a `ConfigError` (`config_error`)."""
    try:
        return model.model_validate(dict(values))
    except ValidationError as exc:
        raise config_error(model, exc) from None


# -- errors --------------------------------------------------------------------------------------

def config_error(model: type[Arguments], exc: ValidationError) -> ConfigError:
    """The first error of ``exc`` as the package's one-line `ConfigError`. A validator's own
    `ConfigError` (its message already names the field) is returned as it is; pydantic's type
    and range errors become "<field>: <what is allowed>, got <value>", the field written as
    ``angles[2]`` or ``physics_params.friction`` for a nested one."""
    error = exc.errors(include_url=False)[0]
    raised = error.get("ctx", {}).get("error")
    if isinstance(raised, BounceGymError):
        return raised if isinstance(raised, ConfigError) else ConfigError(str(raised))
    where = location(error["loc"])
    return ConfigError(f"{where}: {_allowed(model, error)}, got {error['input']!r}")


def location(loc: Sequence[str | int]) -> str:
    """A pydantic error location as a field path (`bounce_gym.validate.field_path`):
    ``("angles", 2)`` -> ``angles[2]``; the arguments as a whole when empty."""
    return field_path(loc) or "arguments"


def _allowed(model: type[Arguments], error: Mapping) -> str:
    """What the field of ``error`` allows, in the package's words."""
    kind, ctx = error["type"], error.get("ctx", {})
    field = model.model_fields.get(error["loc"][0]) if len(error["loc"]) == 1 else None
    if kind == "literal_error":
        choices = _literals(accepted(field)) if field is not None else None
        return f"expected one of {choices}" if choices else f"expected {ctx['expected']}"
    if kind == "bool_type":
        return "expected True or False"
    integer = kind.startswith("int_") or (field is not None and _is_int(accepted(field)))
    if kind == "finite_number":
        return "expected a finite number"
    if kind.startswith(("int_", "float_", "greater_", "less_")):
        what = "an integer" if integer else "a number"
        bounds = _bounds(field.metadata) if field is not None else _ctx_bounds(ctx)
        return f"expected {what}{bounds}"
    return error["msg"][:1].lower() + error["msg"][1:]


def _literals(annotation: object) -> list | None:
    """The choices of a ``Literal`` (inside an optional) annotation, else None."""
    if typing.get_origin(annotation) is Literal:
        return list(typing.get_args(annotation))
    for arg in typing.get_args(annotation):
        if (found := _literals(arg)) is not None:
            return found
    return None


def _is_int(annotation: object) -> bool:
    """Whether an annotation is ``int``, optional or not."""
    annotation = bare(annotation)
    return annotation is int or int in typing.get_args(annotation)


def _bounds(metadata: Sequence) -> str:
    """" in [0, 10]", " > 0", ... from a field's bounds (``Field(ge=..., le=...)``); "" if
    none."""
    found = {key: getattr(item, key) for item in metadata for key in ("gt", "ge", "lt", "le")
             if getattr(item, key, None) is not None}
    return _ctx_bounds(found)


def _ctx_bounds(found: Mapping) -> str:
    low = ("(", found["gt"]) if "gt" in found else ("[", found["ge"]) if "ge" in found else None
    high = (")", found["lt"]) if "lt" in found else ("]", found["le"]) if "le" in found else None
    if low and high:
        return f" in {low[0]}{low[1]:g}, {high[1]:g}{high[0]}"
    if low:
        return f" {'>' if low[0] == '(' else '>='} {low[1]:g}"
    if high:
        return f" {'<' if high[0] == ')' else '<='} {high[1]:g}"
    return ""


# -- what follows from a declaration -------------------------------------------------------------

def signature(cls: type[TakesArguments]) -> inspect.Signature:
    """``cls``'s own named ``__init__`` parameters (``render_mode``, ``max_cycles``, ...), then
    every argument of its model it takes, keyword-only, with its default and annotation."""
    own = [parameter for parameter in
           inspect.signature(cls.__init__, eval_str=True).parameters.values()
           if parameter.kind not in (inspect.Parameter.VAR_KEYWORD,
                                     inspect.Parameter.VAR_POSITIONAL)][1:]
    fields = cls.options_model.model_fields
    declared = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY,
                                  default=cls.option_defaults.get(name, fields[name].default),
                                  annotation=bare(accepted(fields[name])))
                for name in cls.taken()]
    return inspect.Signature([*own, *declared])


def bare(annotation: object) -> object:
    """``annotation`` without the validation metadata of ``Annotated`` (inside unions too)."""
    if typing.get_origin(annotation) is Annotated:
        return bare(typing.get_args(annotation)[0])
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return functools.reduce(operator.or_, map(bare, typing.get_args(annotation)))
    return annotation


def type_name(annotation: object) -> str:
    """A short readable name of a field's type: ``'a' | 'b' | None``, ``Sequence[float]``."""
    annotation = bare(annotation)
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if annotation is type(None) or annotation is None:
        return "None"
    if origin is Literal:
        return " | ".join(repr(arg) for arg in args)
    if origin in (typing.Union, types.UnionType):
        return " | ".join(type_name(arg) for arg in args)
    if origin is not None:
        name = getattr(origin, "__name__", str(origin))
        return f"{name}[{', '.join(type_name(arg) for arg in args)}]"
    if annotation is Any:
        return "Any"
    return getattr(annotation, "__name__", str(annotation))


def arguments_table(cls: type[TakesArguments], registered: Mapping | None = None) -> list[str]:
    """The Markdown table (name, type, default, description) of the arguments ``cls`` takes;
    with ``registered`` (an id's registered keyword arguments) a column of the id's values
    beside the class's defaults ("—" where the id keeps the default)."""
    fields = cls.options_model.model_fields
    header = ["argument", "type", *(["registered value"] if registered is not None else []),
              "default", "description"]
    lines = [_row(header), _row(["---"] * len(header))]
    for name in cls.taken():
        default = cls.option_defaults.get(name, fields[name].default)
        cells = [f"`{name}`", f"`{type_name(accepted(fields[name]))}`"]
        if registered is not None:
            cells.append(f"`{registered[name]!r}`" if name in registered else "—")
        # a pipe inside a code span does not split a cell (Python-Markdown's tables)
        description = " ".join((fields[name].description or "").split()).replace("|", "\\|")
        lines.append(_row([*cells, f"`{default!r}`", description]))
    return lines


def _row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def json_schema(env: str | type[TakesArguments]) -> dict:
    """The JSON Schema of the keyword arguments of an env: of env class ``env`` (the arguments
    of its model it takes, with its defaults), or of a registered id (its class's, with the
    registered arguments as defaults: what ``gym.make(id, **kwargs)`` or
    ``pettingzoo.make(..., id, **kwargs)`` takes as ``kwargs``). For configuration files."""
    cls, registered = (env, {}) if isinstance(env, type) else registered_env(env)
    schema = cls.options_model.model_json_schema()
    properties = {name: dict(schema["properties"][name]) for name in cls.taken()}
    defaults = {**cls.option_defaults, **registered}
    for name in properties.keys() & defaults.keys():
        properties[name]["default"] = to_jsonable_python(defaults[name])
    title = f"{env if isinstance(env, str) else cls.__name__} arguments"
    return {**schema, "title": title, "properties": properties}


def registered_env(env_id: str) -> tuple[type[TakesArguments], dict]:
    """The env class a registered id builds and the keyword arguments it is registered with
    (a PettingZoo id's class: the return annotation of its ``parallel_env``)."""
    import gymnasium as gym
    import pettingzoo

    if env_id in pettingzoo.parallel_registry:
        spec = pettingzoo.parallel_registry[env_id]
        module, name = spec.entry_point.split(":")
        maker = getattr(importlib.import_module(module), name)
        cls = typing.get_type_hints(maker)["return"]
    else:
        spec = gym.spec(env_id)  # raises gymnasium's error naming the id if it is unknown
        cls = gym.envs.registration.load_env_creator(spec.entry_point) \
            if isinstance(spec.entry_point, str) else spec.entry_point
    if not (isinstance(cls, type) and issubclass(cls, TakesArguments)):
        raise ConfigError(f"env: {env_id!r} is not one of bounce_gym's environments")
    return cls, dict(spec.kwargs or {})
