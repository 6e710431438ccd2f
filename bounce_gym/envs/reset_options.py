"""The check of ``reset(options=...)`` shared by every env core."""

from __future__ import annotations

import warnings
from collections.abc import Mapping

from bounce_gym.errors import ConfigError


def checked_reset_options(options: Mapping | None, allowed: frozenset,
                          strict: bool = True) -> Mapping:
    """``options`` (``{}`` for None) once it is a mapping whose keys are all ``allowed``.

    Unknown keys raise `ConfigError`; with ``strict=False`` (PettingZoo's API test passes
    arbitrary options) they only warn, at the caller of the env's ``reset``.
    """
    options = {} if options is None else options
    if not isinstance(options, Mapping):
        raise ConfigError(f"reset options: expected a dict, got {type(options).__name__}")
    unknown = sorted(set(options) - allowed)
    if unknown:
        message = f"reset options: unknown keys {unknown}; allowed are {sorted(allowed)}"
        if strict:
            raise ConfigError(message)
        warnings.warn(message + " (ignored)", UserWarning, stacklevel=4)
    return options
