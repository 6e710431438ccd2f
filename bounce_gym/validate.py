"""Checks of user-given numbers and flags, shared by every layer that reads configuration.

The envs' options, the noise models and the tasks all take numbers from users. A value is
accepted only if it already is one: a bool is not a number (``True`` would silently become 1), a
string is not a number (``"0.5"`` is rejected, not parsed), and a complex value is not a real
number (its imaginary part would be dropped). Every rejection is a `ConfigError` naming the field
and what is allowed. The module imports only `bounce_gym.errors`, so any layer may use it.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable, Mapping

import numpy as np

from bounce_gym.errors import ConfigError, UnknownArgumentError


def _is_number(value: object) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float | np.integer | np.floating)


def number(field: str, value: object, *, minimum: float | None = None,
           strict: bool = False, maximum: float | None = None) -> float:
    """``value`` as a finite float, if it is a real number (int or float, Python or numpy, not
    bool) at least ``minimum`` (greater than it if ``strict``) and at most ``maximum``."""
    if not _is_number(value):
        raise ConfigError(f"{field}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ConfigError(f"{field}: expected a finite number, got {value!r}")
    below = minimum is not None and (value <= minimum if strict else value < minimum)
    if maximum is not None and (below or value > maximum):
        low = "(-inf" if minimum is None else f"{'(' if strict else '['}{minimum:g}"
        raise ConfigError(f"{field}: expected a number in {low}, {maximum:g}], got {value:g}")
    if below:
        raise ConfigError(f"{field}: expected a number {'>' if strict else '>='} {minimum}, "
                          f"got {value!r}")
    return value


def integer(field: str, value: object, minimum: int, maximum: int | None = None) -> int:
    """``value`` as an int, if it is an integer (Python or numpy, not bool) in
    [``minimum``, ``maximum``] (no upper bound if ``maximum`` is None)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum \
            or (maximum is not None and value > maximum):
        allowed = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"
        raise ConfigError(f"{field}: expected an integer {allowed}, got {value!r}")
    return int(value)


def numbers(field: str, value: object) -> np.ndarray:
    """``value`` (a number, a nested sequence of numbers or a real array) as a finite float64
    array. Every entry must be a number as `number` means it: a bool, string or complex value
    anywhere (``[True, 1.5]``, ``["1", 2]``), or a ragged nesting, is rejected, not converted."""
    array = value if isinstance(value, np.ndarray) else np.asarray(value, dtype=object)
    if array.dtype == object and all(_is_number(x) for x in array.flat):
        array = array.astype(np.float64)
    if array.dtype.kind not in "iuf":
        raise ConfigError(f"{field}: expected real numbers (not bools, strings or complex) "
                          f"in a regular nesting, got {value!r}")
    array = array.astype(np.float64)
    if not np.all(np.isfinite(array)):
        raise ConfigError(f"{field}: expected finite numbers, got {value!r}")
    return array


def flag(field: str, value: object) -> bool:
    """``value`` if it is ``True`` or ``False`` (numpy bools included); nothing else is a flag."""
    if not isinstance(value, bool | np.bool_):
        raise ConfigError(f"{field}: expected True or False, got {value!r}")
    return bool(value)


def unexpected(who: str, name: str, valid: Iterable[str] = ()) -> UnknownArgumentError:
    """The error of a keyword argument ``name`` that ``who`` does not take: Python's message
    for it, followed by the closest of the ``valid`` names in parentheses if one is close
    (`did_you_mean`), as a `ConfigError` that is also the `TypeError` Python raises."""
    hint = did_you_mean([name], valid)
    return UnknownArgumentError(f"{who}() got an unexpected keyword argument {name!r}"
                                + (f" ({hint})" if hint else ""))


def unknown_keys(field: str, mapping: Mapping, allowed: Iterable[str]) -> None:
    """Refuse the keys of ``mapping`` not among ``allowed``: one `ConfigError` naming them, the
    allowed keys they may misspell (`did_you_mean`) and every allowed key."""
    allowed = sorted(allowed)
    unknown = sorted(set(mapping) - set(allowed), key=str)
    if unknown:
        hint = did_you_mean(unknown, allowed)
        raise ConfigError(f"{field}: unknown keys {unknown}{f' ({hint})' if hint else ''}; "
                          f"allowed are {allowed}")


def did_you_mean(names: Iterable[object], valid: Iterable[object]) -> str:
    """``did you mean 'seeds'?`` for a misspelled name (one of ``names`` close to one of the
    ``valid`` names, by `difflib.get_close_matches`); for several, which valid name each stands
    for (``did you mean 'seeds' for 'seed', 'world' for 'wrld'?``); ``""`` if none is close."""
    names = [str(name) for name in names]
    valid = [str(name) for name in valid]
    pairs = [(name, close[0]) for name in names
             if (close := difflib.get_close_matches(name, valid, n=1))]
    if not pairs:
        return ""
    if len(names) == 1:
        return f"did you mean {pairs[0][1]!r}?"
    return "did you mean " + ", ".join(f"{match!r} for {name!r}" for name, match in pairs) + "?"


def field_path(loc: Iterable[str | int], at: str = "") -> str:
    """A validation error's location as the package's field path: ``("angles", 2)`` ->
    ``angles[2]``, ``("physics_params", "friction")`` -> ``physics_params.friction``; below
    ``at`` when given (``config.experiments`` + ``(2, "seeds")`` ->
    ``config.experiments[2].seeds``)."""
    text = at
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text
