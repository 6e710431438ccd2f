"""The base of the configuration models (pydantic): one declaration per key — its type, default
and description — from which the JSON Schema (`bounce_gym_experiments.schema`) and the docs'
configuration reference are generated, and the package's own one-line `ConfigError`.

A model is checked with `ConfigModel.check` (never ``model_validate`` directly): pydantic's
``ValidationError`` does not escape; it becomes ``<where>.<field path>: <what is allowed>, got
<value>``, e.g. ``config.experiments[2].seeds: ...``. Validators that check a rule call the
package's own checks (`bounce_gym.validate`) with the full field path, ``located(info, key)``,
and their `ConfigError` is handed on unchanged. Unknown keys are refused before any other check,
naming the key meant (`bounce_gym.validate.unknown_keys`, did-you-mean).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError, ValidationInfo, model_validator

from bounce_gym.errors import ConfigError
from bounce_gym.validate import field_path, unknown_keys

#: pydantic's type errors and the type names of the package's messages
_TYPE_NAMES = {"int_type": "int", "string_type": "str", "bool_type": "bool", "list_type": "list",
               "dict_type": "dict", "model_type": "dict", "float_type": "float"}


class ConfigModel(BaseModel):
    """A mapping of a configuration file: no key beyond the declared ones, values of the declared
    types (strict: ``true`` is not an integer, ``"5"`` not a number)."""

    model_config = ConfigDict(extra="forbid", strict=True, validate_default=False)

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any, info: ValidationInfo) -> Any:
        if isinstance(data, Mapping):
            unknown_keys(where(info), data, cls.model_fields)
        return data

    @classmethod
    def check(cls, data: object, at: str):
        """``data`` checked as this model; a mistake raises `ConfigError` located at ``at``
        (e.g. ``config.experiments[2]``)."""
        if not isinstance(data, Mapping):
            raise ConfigError(f"{at}: expected a mapping, got {type(data).__name__}")
        try:
            return cls.model_validate(dict(data), context={"where": at})
        except ValidationError as exc:
            raise configuration_error(exc, at) from None


def where(info: ValidationInfo) -> str:
    """The field path of the model being checked (``ConfigModel.check``'s ``at``)."""
    return (info.context or {}).get("where", "config")


def located(info: ValidationInfo, key: str | None = None) -> str:
    """The field path of ``key`` (default: the field being validated) of the model being
    checked."""
    return f"{where(info)}.{key or info.field_name}"


def configuration_error(exc: ValidationError, at: str) -> ConfigError:
    """The first mistake of a pydantic ``ValidationError`` as the package's one-line
    `ConfigError` (a `ConfigError` a validator raised, unchanged)."""
    error = exc.errors()[0]
    raised = (error.get("ctx") or {}).get("error")
    if isinstance(raised, ConfigError):
        return raised
    loc = error["loc"]
    if error["type"] == "missing":
        return ConfigError(f"{field_path(loc[:-1], at)}: missing key {loc[-1]!r}")
    field = field_path(loc, at)
    if error["type"] in _TYPE_NAMES:
        return ConfigError(f"{field}: expected {_TYPE_NAMES[error['type']]}, got "
                           f"{type(error['input']).__name__}")
    if isinstance(raised, Exception):
        return ConfigError(f"{field}: {raised}")
    return ConfigError(f"{field}: {error['msg']}, got {shorten(error.get('input'))}")


def shorten(value: object) -> str:
    """``repr(value)``, cut to 80 characters."""
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:77]}..."
