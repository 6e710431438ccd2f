"""Map files: reading and writing worlds as JSON or YAML.

Schema
------
A map is one mapping (a JSON object or a YAML mapping) in one of two forms. Every key not listed
here is an error, and so is a missing required key or a value of the wrong type.

**Polygon form** (any world)::

    name: two_rooms                          # required, non-empty string
    description: "Nilles et al. 2021 ..."    # optional string
    outer: [[0, 0], [8, 0], [8, 2], ...]     # required: >= 3 vertices [x, y], any orientation
    holes:                                   # optional (default: no holes): a list of rings,
      - [[2, 2], [3, 2], [3, 3]]             #   each >= 3 vertices [x, y], any orientation

Coordinates are numbers (integers or floats; booleans are not numbers here; in YAML write
exponents with a dot, ``1.0e3``, since YAML 1.1 reads ``1e3`` as a string). A closing vertex
equal to the first one is allowed and dropped. The outer ring is stored counter-clockwise and the
holes clockwise, whatever the file's orientation (see `bounce_gym.worlds.world.World`).

**Grid form** (worlds made of square cells, as in the cell-mapping papers)::

    name: grid_10x10                         # required, non-empty string
    description: "..."                       # optional string
    grid:                                    # required: rows of equal length, TOP row first,
      - "...#......"                         #   '.' = free cell, '#' = blocked cell
      - "...#......"
    cell_size: 1.0                           # optional number > 0 (default 1)

Cell ``(row, col)`` of the grid (row 0 at the **bottom**, i.e. the last line of the file) is the
square ``[col*s, (col+1)*s] x [row*s, (row+1)*s]``; the world is the union of the free cells and
must be one 4-connected region without diagonal pinches (`bounce_gym.worlds.grid`). In YAML,
quote the rows: an unquoted ``#`` starts a comment.

Exactly one of ``outer`` and ``grid`` must be present; ``holes`` belongs to the polygon form and
``cell_size`` to the grid form.

Limits: a map file holds at most `MAX_FILE_BYTES` (128 MiB, room for a 10 000 x 10 000 grid),
a ring at most `MAX_VERTICES` (10**6) vertices, lists and mappings nest at most `MAX_DEPTH`
(32) deep (a map needs 4: mapping, holes, ring, vertex), and a YAML map, its aliases expanded,
has at most `MAX_NODES` nodes. Larger or deeper files raise `bounce_gym.errors.MapFormatError`
before they are parsed into objects (`bounce_gym.documents`, the package's one reader of YAML
and JSON, which also refuses control characters in strings and keys that are not strings).

File formats are chosen by suffix: ``.json``, ``.yaml`` or ``.yml`` (case-insensitive). Files
are UTF-8. Duplicate keys are rejected. Every schema violation raises
`bounce_gym.errors.MapFormatError` whose message names the file, the field and what is allowed;
geometry that does not form a valid world raises the same error with the reason from `World`.

Writing is atomic: `save` writes a temporary file in the target directory and moves it into place
with `os.replace`, so readers never see a half-written map. ``load(save(world, path))`` equals
``world`` exactly (floats are written with their shortest round-tripping representation).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping
from numbers import Real
from pathlib import Path

import numpy as np
import yaml

from bounce_gym.documents import Limits, read_document
from bounce_gym.errors import InvalidWorldError, MapFormatError
from bounce_gym.files import atomic_write
from bounce_gym.worlds.grid import parse_ascii, to_ascii, world_from_grid
from bounce_gym.worlds.world import World

__all__ = ["SUFFIXES", "from_dict", "load", "load_dict", "save", "to_dict"]

#: File suffixes understood by `load` and `save`, mapped to their format.
SUFFIXES = {".json": "json", ".yaml": "yaml", ".yml": "yaml"}

#: Largest map file, in bytes.
MAX_FILE_BYTES = 128 * 2**20
#: Most vertices of one ring.
MAX_VERTICES = 10**6
#: Deepest nesting of lists and mappings in a map file (a map needs 4: mapping, holes, ring,
#: vertex).
MAX_DEPTH = 32
#: Most YAML nodes of a map file, every alias counted as a copy of its anchor's node: room for
#: ten rings of `MAX_VERTICES` vertices.
MAX_NODES = 2**25

_POLYGON_KEYS = ("name", "description", "outer", "holes")
_GRID_KEYS = ("name", "description", "grid", "cell_size")
_ALL_KEYS = ("name", "description", "outer", "holes", "grid", "cell_size")


# -- dictionaries -----------------------------------------------------------------------------
def from_dict(d: Mapping, *, source: str = "map") -> World:
    """Build a `World` from a map dictionary in the polygon or the grid form (module docstring).

    Args:
        d: the map dictionary.
        source: a label for error messages (the file name when called by `load`).

    Raises:
        MapFormatError: the dictionary does not follow the schema, or its geometry is invalid.
    """
    if not isinstance(d, Mapping):
        raise MapFormatError(
            f"{source}: expected a mapping with keys {list(_ALL_KEYS)}, got {type(d).__name__}"
        )
    unknown = [k for k in d if k not in _ALL_KEYS]
    if unknown:
        raise MapFormatError(
            f"{source}: unknown key(s) {', '.join(repr(k) for k in unknown)}; allowed keys are "
            f"{list(_POLYGON_KEYS)} (polygon form) or {list(_GRID_KEYS)} (grid form)"
        )
    if "name" not in d:
        raise MapFormatError(f"{source}: missing required key 'name' (a non-empty string)")
    name = d["name"]
    if not isinstance(name, str) or not name.strip():
        raise MapFormatError(f"{source}: 'name' must be a non-empty string, got {name!r}")
    if "description" in d and not isinstance(d["description"], str):
        raise MapFormatError(
            f"{source}: 'description' must be a string, got {type(d['description']).__name__}"
        )
    has_outer, has_grid = "outer" in d, "grid" in d
    if has_outer == has_grid:
        what = "both" if has_outer else "neither"
        raise MapFormatError(
            f"{source}: map has {what} of 'outer' and 'grid'; give exactly one: 'outer' "
            "(polygon form, with optional 'holes') or 'grid' (grid form, with optional 'cell_size')"
        )
    if has_outer:
        if "cell_size" in d:
            raise MapFormatError(
                f"{source}: 'cell_size' belongs to the grid form; the polygon form ('outer') "
                f"allows only {list(_POLYGON_KEYS)}"
            )
        outer = _ring(d["outer"], "outer", source)
        holes_value = d.get("holes", [])
        if not isinstance(holes_value, list | tuple):
            raise MapFormatError(
                f"{source}: 'holes' must be a list of rings (each a list of [x, y] vertices), "
                f"got {type(holes_value).__name__}"
            )
        holes = [_ring(h, f"holes[{k}]", source) for k, h in enumerate(holes_value)]
        try:
            return World(outer, holes, name=name)
        except InvalidWorldError as exc:
            raise MapFormatError(f"{source}: invalid polygon: {exc}") from exc
    if "holes" in d:
        raise MapFormatError(
            f"{source}: 'holes' belongs to the polygon form; the grid form ('grid') allows only "
            f"{list(_GRID_KEYS)} (block cells with '#' instead)"
        )
    rows = d["grid"]
    if (
        not isinstance(rows, list | tuple)
        or not rows
        or not all(isinstance(r, str) for r in rows)
    ):
        raise MapFormatError(
            f"{source}: 'grid' must be a non-empty list of strings (rows, top row first; "
            "'.' free, '#' blocked)"
        )
    cell_size = d.get("cell_size", 1.0)
    if (
        isinstance(cell_size, bool)
        or not isinstance(cell_size, Real)
        or not np.isfinite(float(cell_size))
        or cell_size <= 0
    ):
        raise MapFormatError(f"{source}: 'cell_size' must be a finite number > 0, got {cell_size!r}")
    try:
        free = parse_ascii(list(rows))
        return world_from_grid(free, float(cell_size), name=name)
    except InvalidWorldError as exc:
        note = ""
        if "between rows" in str(exc):
            note = " (rows counted from the bottom: row 0 is the last line of 'grid')"
        raise MapFormatError(f"{source}: invalid {exc}{note}") from exc


def to_dict(
    world: World,
    *,
    grid: bool | float | np.ndarray | None = None,
    cell_size: float = 1.0,
    description: str | None = None,
) -> dict:
    """The map dictionary of ``world`` (see the module docstring).

    Args:
        world: the world to describe.
        grid: ``None`` for the polygon form. For the grid form either a cell size (a number > 0,
            or ``True`` for ``cell_size``), in which case the grid is ``world.occupancy`` at that
            size, or a boolean array ``free[row, col]`` (row 0 at the bottom) drawn with cells of
            ``cell_size``.
        cell_size: cell size used with ``grid=True`` or a grid array.
        description: optional free text stored under ``description``.

    Raises:
        MapFormatError: the grid form was asked for but does not describe exactly ``world`` (the
            world is not a union of grid cells with a corner at the origin).
    """
    if not isinstance(world, World):
        raise MapFormatError(f"world: expected a World, got {type(world).__name__}")
    if description is not None and not isinstance(description, str):
        raise MapFormatError(f"description: must be a string, got {type(description).__name__}")
    d: dict = {"name": world.name}
    if description is not None:
        d["description"] = description
    if grid is None:
        d["outer"] = world.outer.tolist()
        d["holes"] = [h.tolist() for h in world.holes]
        return d
    if isinstance(grid, np.ndarray | list | tuple):
        free = np.asarray(grid)
        size = cell_size
    elif grid is True:
        size = cell_size
        free = None
    elif isinstance(grid, Real) and not isinstance(grid, bool):
        size = grid
        free = None
    else:
        raise MapFormatError(
            f"grid: expected None (polygon form), True, a cell size > 0 or a boolean array, "
            f"got {grid!r}"
        )
    if isinstance(size, bool) or not isinstance(size, Real) or not np.isfinite(size) or size <= 0:
        raise MapFormatError(f"cell_size: must be a finite number > 0, got {size!r}")
    if free is None:
        free = world.occupancy(float(size))
    try:
        rebuilt = world_from_grid(free, float(size), name=world.name)
    except InvalidWorldError as exc:
        raise MapFormatError(f"grid: does not describe a valid world: {exc}") from exc
    if rebuilt != world:
        raise MapFormatError(
            f"grid: world {world.name!r} is not the union of the grid's free cells of size "
            f"{size} with a corner at the origin; save it in the polygon form (grid=None)"
        )
    d["grid"] = to_ascii(free)
    d["cell_size"] = float(size)
    return d


# -- files ------------------------------------------------------------------------------------
def load(path: str | os.PathLike) -> World:
    """Read a map file (``.json``, ``.yaml`` or ``.yml``) and build its `World`.

    Raises:
        MapFormatError: unknown suffix, a missing or unreadable file, text that is not valid
            UTF-8/JSON/YAML, or a map that does not follow the schema.
    """
    path = Path(path)
    return from_dict(load_dict(path), source=str(path))


def load_dict(path: str | os.PathLike) -> dict:
    """Read a map file into its dictionary, checking the file format (not yet the schema).

    Use `from_dict` (or `load`) to validate and build the world; this gives access to the
    optional ``description``. The file is read by `bounce_gym.documents.read_document` within
    `MAX_FILE_BYTES`, `MAX_DEPTH` and `MAX_NODES`.
    """
    path = Path(path)
    fmt = _format(path)
    data = read_document(path, fmt=fmt, error=MapFormatError,
                         limits=Limits(bytes=MAX_FILE_BYTES, depth=MAX_DEPTH, nodes=MAX_NODES))
    if not isinstance(data, dict):
        raise MapFormatError(
            f"{path}: expected a mapping with keys {list(_ALL_KEYS)} at the top level, "
            f"got {'an empty file' if data is None else type(data).__name__}"
        )
    return data


def save(
    world: World,
    path: str | os.PathLike,
    *,
    grid: bool | float | np.ndarray | None = None,
    cell_size: float = 1.0,
    description: str | None = None,
) -> Path:
    """Write ``world`` to ``path`` atomically; the suffix chooses JSON or YAML.

    Args:
        world: the world to write.
        path: target file, ending in ``.json``, ``.yaml`` or ``.yml``; its directory must exist.
        grid: as in `to_dict` (``None`` writes the polygon form).
        cell_size: as in `to_dict`.
        description: as in `to_dict`.

    Returns:
        The path written, so that ``load(save(world, path)) == world``.

    Raises:
        MapFormatError: unknown suffix, or a grid form that does not describe ``world``.
    """
    path = Path(path)
    fmt = _format(path)
    d = to_dict(world, grid=grid, cell_size=cell_size, description=description)
    if fmt == "json":
        text = json.dumps(d, indent=2, ensure_ascii=False, allow_nan=False)
        text = _PAIR.sub(r"[\1, \2]", text) + "\n"  # one vertex per line
    else:
        text = yaml.safe_dump(
            d, sort_keys=False, default_flow_style=None, allow_unicode=True, width=100
        )
    atomic_write(path, text.encode("utf-8"))
    return path


# -- helpers ----------------------------------------------------------------------------------
#: A vertex [x, y] as ``json.dumps(indent=2)`` spreads it over four lines. JSON strings cannot
#: hold raw newlines, so this never matches inside the name or the description.
_NUM = r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"
_PAIR = re.compile(rf"\[\n\s+({_NUM}),\n\s+({_NUM})\n\s+\]")


def _format(path: Path) -> str:
    fmt = SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise MapFormatError(
            f"{path}: unknown map file suffix {path.suffix!r}; allowed are {sorted(SUFFIXES)}"
        )
    return fmt


def _ring(value: object, field: str, source: str) -> list[list[float]]:
    allowed = "a list of at least 3 vertices, each a pair of numbers [x, y]"
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, list | tuple):
        raise MapFormatError(f"{source}: '{field}' must be {allowed}, got {type(value).__name__}")
    if not 3 <= len(value) <= MAX_VERTICES:
        raise MapFormatError(
            f"{source}: '{field}' must be {allowed} and at most {MAX_VERTICES}, "
            f"got {len(value)} vertices"
        )
    ring = []
    for k, vertex in enumerate(value):
        if (
            not isinstance(vertex, list | tuple)
            or len(vertex) != 2
            or not all(isinstance(c, Real) and not isinstance(c, bool) for c in vertex)
        ):
            raise MapFormatError(
                f"{source}: '{field}' vertex {k} must be a pair of numbers [x, y], got {vertex!r}"
            )
        try:
            ring.append([float(vertex[0]), float(vertex[1])])
        except OverflowError:  # an int beyond a float's range
            raise MapFormatError(f"{source}: '{field}' vertex {k}: a coordinate is too large "
                                 "for a float") from None
    return ring
