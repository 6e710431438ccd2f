"""The named map zoo: ``get(name)`` returns a `World`, ``names()`` lists the stored maps.

Stored maps are the YAML files in ``bounce_gym/worlds/maps/`` (schema: `bounce_gym.worlds.io`);
each carries a ``description`` saying where it comes from and, for reconstructions of maps
that the papers only show as figures, what is known and what was invented (`describe`).

Besides the stored maps, ``regular_<n>`` for any integer ``3 <= n <= 10000`` (`MAX_REGULAR`;
written without leading zeros) is the regular n-gon with circumradius 10 centred at (10, 10), first vertex at angle 0,
i.e. vertex ``k`` is ``(10 + 10 cos(2 pi k / n), 10 + 10 sin(2 pi k / n))``, counter-clockwise.

Worlds are immutable, so `get` caches them and returns the same object on every call.
"""

from __future__ import annotations

import re
from functools import cache, lru_cache
from importlib import resources

import numpy as np

from bounce_gym.errors import InvalidWorldError
from bounce_gym.worlds import io
from bounce_gym.worlds.world import World

__all__ = ["describe", "get", "names"]

_MAPS_PACKAGE = "bounce_gym.worlds"
_MAPS_DIR = "maps"
_REGULAR = re.compile(r"regular_([1-9][0-9]*)")

#: Largest ``n`` of ``regular_<n>``: beyond it the edges are shorter than 1e-2 and the polygon
#: is a circle for every practical purpose.
MAX_REGULAR = 10_000
#: Regular n-gons: circumradius and centre.
REGULAR_RADIUS = 10.0
REGULAR_CENTER = (10.0, 10.0)


def names() -> list[str]:
    """Sorted names of the stored maps (the ``regular_<n>`` family is not listed)."""
    return list(_stored_names())


def get(name: str) -> World:
    """The zoo world called ``name`` (cached; worlds are immutable).

    Raises:
        InvalidWorldError: unknown name (the message lists the available names), or
            ``regular_<n>`` with ``n`` outside ``[3, MAX_REGULAR]``.
    """
    if not isinstance(name, str):
        raise InvalidWorldError(f"name: expected a string, got {type(name).__name__}")
    n = _regular_size(name)
    if n is not None:
        return _regular(n)
    if name in _stored_names():
        return _stored(name)
    raise InvalidWorldError(
        f"unknown world {name!r}; available: {', '.join(_stored_names())}, "
        f"and regular_<n> for any integer 3 <= n <= {MAX_REGULAR}"
    )


def describe(name: str) -> str:
    """The ``description`` of a zoo map: its source and what was reconstructed or invented."""
    if isinstance(name, str) and _regular_size(name) is not None:
        return (
            f"Regular {name[len('regular_'):]}-gon, circumradius {REGULAR_RADIUS:g} centred at "
            f"{REGULAR_CENTER}, first vertex at angle 0, counter-clockwise."
        )
    get(name)  # raises the standard error for unknown names
    with resources.as_file(_map_file(name)) as path:
        return str(io.load_dict(path).get("description", ""))


# -- internals --------------------------------------------------------------------------------
def _regular_size(name: str) -> int | None:
    """``n`` if ``name`` is ``regular_<n>`` (checked against `MAX_REGULAR`), else None."""
    match = _REGULAR.fullmatch(name)
    if match is None:
        return None
    n = int(match.group(1))
    if not 3 <= n <= MAX_REGULAR:
        raise InvalidWorldError(
            f"world {name!r}: regular_<n> needs an integer 3 <= n <= {MAX_REGULAR}, got {n}"
        )
    return n


def _map_file(name: str):
    return resources.files(_MAPS_PACKAGE).joinpath(_MAPS_DIR).joinpath(f"{name}.yaml")


@lru_cache(maxsize=1)
def _stored_names() -> tuple[str, ...]:
    folder = resources.files(_MAPS_PACKAGE).joinpath(_MAPS_DIR)
    return tuple(
        sorted(p.name[: -len(".yaml")] for p in folder.iterdir() if p.name.endswith(".yaml"))
    )


@cache
def _stored(name: str) -> World:
    with resources.as_file(_map_file(name)) as path:
        world = io.load(path)
    if world.name != name:
        raise InvalidWorldError(
            f"zoo map file {name}.yaml: 'name' is {world.name!r}; it must match the file name"
        )
    return world


@lru_cache(maxsize=128)
def _regular(n: int) -> World:
    angles = 2.0 * np.pi * np.arange(n) / n
    cx, cy = REGULAR_CENTER
    vertices = np.column_stack(
        (cx + REGULAR_RADIUS * np.cos(angles), cy + REGULAR_RADIUS * np.sin(angles))
    )
    return World(vertices, name=f"regular_{n}")
