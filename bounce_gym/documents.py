"""The one reader of the YAML and JSON documents the package is given: evaluation and training
configurations, hyperparameter files, search spaces, map files, and the JSON it reads back
(manifests, model metadata).

`read_document` reads a file, `parse_document` bytes already in memory. Before any Python
object that could be large is built, a document must pass these checks (`Limits` holds the
numbers; the defaults suit configurations):

* size: at most ``bytes`` bytes (default 4 MiB), read no further than that;
* text: UTF-8 (a leading byte-order mark is dropped); no string, key or value, escapes decoded,
  holds a control character other than tab, line feed and carriage return (so no NUL, DEL or
  C1 control), nor a lone UTF-16 surrogate;
* nesting: lists and mappings nest at most ``depth`` deep (default 32). YAML is measured on the
  parser's event stream (flow brackets and block indentation alike), JSON by counting every
  opening bracket against the closing ones, those inside strings included, so neither reaches
  a recursive parser too deep;
* aliases (YAML): the document has at most ``nodes`` nodes (default 120,000: room for the
  100,000 seeds an evaluation may list, while any document is read in well under a second)
  and its strings at most ``bytes`` characters, with every alias counted as a full copy of
  the node it names, each anchored node's size worked out once, as the events stream by; so a
  "billion laughs" of nested aliases, or of one long string, is refused without being
  expanded, and so is an alias to a node that contains it;
* numbers: an integer has at most `MAX_DIGITS` (100) digits, in any base YAML writes
  (``0x``, ``0o``, ``1:30``), and a JSON number is finite (no ``NaN``, ``Infinity`` or
  ``1e999``), so no number costs more to read, compare or print than a plain one;
* data: mapping keys are strings and none repeats within its mapping (a merged ``<<`` mapping
  may be overridden, as YAML intends). A JSON document is no bigger than its bytes, so its
  node count needs no check of its own.

YAML is parsed by libyaml (PyYAML's C parser) where PyYAML has it, and built by PyYAML's safe
constructors only: no tag runs code or makes a Python object other than plain data. Every
refusal is one line raised as the caller's error class (`bounce_gym.errors.ConfigError` by
default; `bounce_gym.errors.MapFormatError` for maps) that names the file (or what the caller
calls the bytes) and, where the parser knows it, the line and column.
"""

from __future__ import annotations

import contextlib
import gc
import json
import math
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from bounce_gym.errors import BounceGymError, ConfigError

__all__ = ["FORMATS", "Limits", "parse_document", "read_document"]

#: The formats `parse_document` reads.
FORMATS = ("yaml", "json")
#: The most digits of an integer a document may hold.
MAX_DIGITS = 100
_INT_BOUND = 10**MAX_DIGITS
#: Characters no string of a document may hold: C0 controls but tab, line feed and carriage
#: return; DEL and the C1 controls; lone surrogates (which JSON escapes can make).
_FORBIDDEN = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f\ud800-\udfff]")


@dataclass(frozen=True)
class Limits:
    """What a document may hold (module docstring): ``bytes`` of file, lists and mappings
    nested ``depth`` deep, ``nodes`` YAML nodes (and ``bytes`` characters of strings) with
    aliases expanded."""

    bytes: int = 4 * 2**20
    depth: int = 32
    nodes: int = 120_000


def read_document(path: str | Path, field: str | None = None, *, fmt: str = "yaml",
                  limits: Limits = Limits(), error: type[BounceGymError] = ConfigError
                  ) -> object:
    """The document in the file ``path`` (``fmt``: ``yaml`` or ``json``), checked as the
    module docstring says. Errors start with ``<field>: <path>:`` (``<path>:`` without a
    field); a missing file is ``<field>: file '<path>' does not exist``."""
    path = Path(path)
    lead = f"{field}: " if field else ""
    if not path.is_file():
        what = "is not a file" if path.exists() else "does not exist"
        raise error(f"{lead}file {str(path)!r} {what}")
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > limits.bytes:
                raise error(f"{lead}{path}: {size} bytes; at most {limits.bytes} are allowed")
            data = fh.read(limits.bytes + 1)  # it may have grown since
    except OSError as exc:
        raise error(f"{lead}cannot read {str(path)!r}: {exc.strerror or exc}") from None
    return parse_document(f"{lead}{path}", data, fmt=fmt, limits=limits, error=error)


def parse_document(where: str, data: bytes, *, fmt: str = "yaml", limits: Limits = Limits(),
                   error: type[BounceGymError] = ConfigError) -> object:
    """The document in ``data`` (``fmt``: ``yaml`` or ``json``), checked as the module
    docstring says; a refusal is ``error("<where>: <what is wrong>")``."""
    if fmt not in FORMATS:
        raise ValueError(f"fmt: expected one of {FORMATS}, got {fmt!r}")
    if len(data) > limits.bytes:
        raise error(f"{where}: more than {limits.bytes} bytes; at most {limits.bytes} are "
                    "allowed")
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        raise error(f"{where}: not UTF-8 text: byte {data[exc.start]:#04x} at offset "
                    f"{exc.start}") from None
    try:
        with _collector_paused():
            if fmt == "json":
                return _json(text, data, limits)
            return _yaml(text, limits)
    except _RefusedError as exc:
        raise error(f"{where}: {exc}") from None


@contextlib.contextmanager
def _collector_paused() -> Iterator[None]:
    """Python's cyclic garbage collector paused while a document is built: its objects form no
    cycles, and the passes the collector would make as they are allocated scan every object
    of the process (in one that has imported torch, they doubled the time to read 100,000
    seeds)."""
    if not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


class _RefusedError(Exception):
    """A document failed a check; the message says which and where, without the file."""


def _too_deep(depth: int | str, limits: Limits) -> _RefusedError:
    return _RefusedError(f"lists and mappings nest {depth} deep; at most {limits.depth} are "
                         "allowed")


def _check_text(value: str, mark: yaml.Mark | None = None) -> None:
    found = _FORBIDDEN.search(value)
    if found:
        raise _RefusedError(f"control character U+{ord(found.group()):04X} in the string "
                            f"{value[:40]!r}{_at(mark)}; strings may not hold control "
                            "characters")


# -- JSON -------------------------------------------------------------------------------------
def _json(text: str, data: bytes, limits: Limits) -> object:
    codes = np.frombuffer(data, dtype=np.uint8)
    step = np.isin(codes, (ord("["), ord("{"))).astype(np.int64)
    step -= np.isin(codes, (ord("]"), ord("}")))
    depth = int(np.cumsum(step).max(initial=0))
    if depth > limits.depth:
        raise _too_deep(depth, limits)
    try:
        value = json.loads(text, object_pairs_hook=_unique_pairs, parse_constant=_no_constant,
                           parse_int=_json_int, parse_float=_json_float)
    except json.JSONDecodeError as exc:
        raise _RefusedError(f"not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}") \
            from None
    _check_strings(value)
    return value


def _unique_pairs(pairs: list[tuple[str, object]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise _RefusedError(f"duplicate key {key!r}")
        out[key] = value
    return out


def _no_constant(name: str) -> float:
    raise _RefusedError(f"{name} is not a JSON number; numbers must be finite")


def _json_int(digits: str) -> int:
    if len(digits.lstrip("-")) > MAX_DIGITS:
        raise _too_long(digits)
    return int(digits)


def _json_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _RefusedError(f"the number {text[:40]} is too large; numbers must be finite")
    return value


def _too_long(text: str) -> _RefusedError:
    return _RefusedError(f"the integer {text[:20]}... is too large; integers lie between "
                         f"-10**{MAX_DIGITS} and 10**{MAX_DIGITS}")


def _check_strings(value: object) -> None:
    """Every string of a parsed JSON document (at most `Limits.depth` deep) is clean text."""
    if isinstance(value, str):
        _check_text(value)
    elif isinstance(value, list):
        for item in value:
            _check_strings(item)
    elif isinstance(value, dict):
        for key, item in value.items():
            _check_text(key)
            _check_strings(item)


# -- YAML -------------------------------------------------------------------------------------
#: what a boolean key is told (YAML 1.1 reads yes, no, on and off as booleans)
_QUOTE = " (YAML reads yes, no, on and off as booleans: quote the key)"


class _Loader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """PyYAML's safe loader (libyaml's parser where PyYAML has it) whose mappings have string
    keys, each once."""


def _construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode, deep: bool = False):
    seen: set[str] = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":
            continue  # merged keys may be overridden; checked in their own mapping
        key = loader.construct_object(key_node, deep=True)
        hint = _QUOTE if isinstance(key, bool) else ""
        problem = (f"found a key that is not a string: {key!r}{hint}" if not isinstance(key, str)
                   else f"found duplicate key {key!r}" if key in seen else None)
        if problem:
            raise yaml.constructor.ConstructorError(None, None, problem, key_node.start_mark)
        seen.add(key)
    loader.flatten_mapping(node)
    return loader.construct_mapping(node, deep=deep)


def _construct_int(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> int:
    """An integer of at most `MAX_DIGITS` digits: its value is checked (``0x``, ``0o`` and
    ``1:30`` forms are shorter than their value), and before it is converted, the length of
    its text (which Python would otherwise refuse to convert, or convert slowly). Plain
    decimal digits (the 100,000 seeds of a configuration) are converted at once."""
    text = node.value
    if text.isdigit() and text.isascii() and (text[0] != "0" or text == "0") \
            and len(text) <= MAX_DIGITS:
        return int(text)
    value = None if len(text) > 4 * MAX_DIGITS else \
        yaml.constructor.SafeConstructor.construct_yaml_int(loader, node)
    if value is None or not -_INT_BOUND < value < _INT_BOUND:
        raise yaml.constructor.ConstructorError(None, None, str(_too_long(node.value)),
                                                node.start_mark)
    return value


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
_Loader.add_constructor("tag:yaml.org,2002:int", _construct_int)


def _at(mark: yaml.Mark | None) -> str:
    return f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""


def _yaml(text: str, limits: Limits) -> object:
    try:
        _check_events(text, limits)
        return yaml.load(text, Loader=_Loader)  # noqa: S506 (safe constructors only)
    except yaml.YAMLError as exc:
        if "nesting depth" in str(exc):  # libyaml's own limit, met while scanning ahead
            raise _too_deep(f"more than {limits.depth}", limits) from None
        raise _RefusedError(f"not valid YAML: {_yaml_problem(exc)}") from None


def _yaml_problem(exc: yaml.YAMLError) -> str:
    """A PyYAML error in one line: what was wrong, where."""
    if isinstance(exc, yaml.reader.ReaderError):
        code = exc.character if isinstance(exc.character, int) else ord(exc.character)
        return f"{exc.reason}: U+{code:04X} at character {exc.position}"
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    context = getattr(exc, "context", None)
    return f"{context + ', ' if context else ''}{problem}{_at(getattr(exc, 'problem_mark', None))}"


def _check_events(text: str, limits: Limits) -> None:
    """Depth, expanded size and clean strings, from the parser's events: nothing is built. The
    running totals count every alias as a copy of the node its anchor names, whose size is what
    the totals grew by from its start to its end."""
    starts: list[tuple] = []  # (anchor, nodes, characters) as each open collection started
    sizes: dict[str, tuple[int, int]] = {}  # expanded (nodes, characters) of anchored nodes
    nodes = chars = 0
    for event in yaml.parse(text, Loader=_Loader):
        kind = type(event)
        if kind is yaml.ScalarEvent:  # the most common first: a document is mostly scalars
            _check_text(event.value, event.start_mark)
            nodes, chars = nodes + 1, chars + len(event.value)
            if event.anchor is not None:
                sizes[event.anchor] = (1, len(event.value))
        elif kind is yaml.AliasEvent:
            if event.anchor not in sizes:
                raise _RefusedError(f"the alias *{event.anchor}{_at(event.start_mark)} names no "
                                    "anchor before it, or a node that contains it")
            nodes, chars = nodes + sizes[event.anchor][0], chars + sizes[event.anchor][1]
        elif issubclass(kind, yaml.CollectionStartEvent):
            if len(starts) == limits.depth:
                raise _too_deep(f"more than {limits.depth}", limits)
            starts.append((event.anchor, nodes, chars))
            nodes += 1
        elif issubclass(kind, yaml.CollectionEndEvent):
            anchor, nodes_before, chars_before = starts.pop()
            if anchor is not None:
                sizes[anchor] = (nodes - nodes_before, chars - chars_before)
            continue
        else:
            continue
        if nodes > limits.nodes:
            raise _RefusedError(f"more than {limits.nodes} nodes with its aliases expanded"
                                f"{_at(event.start_mark)}; at most {limits.nodes} are allowed")
        if chars > limits.bytes:
            raise _RefusedError(f"more than {limits.bytes} characters of strings with its "
                                f"aliases expanded{_at(event.start_mark)}; at most "
                                f"{limits.bytes} are allowed")
