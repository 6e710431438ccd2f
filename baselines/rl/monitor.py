"""Per-episode monitor files: SB3's ``monitor.csv`` format, one per training run.

``models/<name>/<run>_seed<seed>.monitor.csv`` holds a first line ``#{"t_start": ..., "env_id":
...}``, a header ``r,l,t[,<outcome>...]`` and one row per finished episode in the order they
finished: return ``r`` (the env's own reward, before any normalisation), length ``l`` (env
steps), wall-clock seconds ``t`` since the run started, and the task's outcome keys the env
reports (``is_success``, ``localized``, ``coverage``; `MONITOR_KEYS`). SB3's
``stable_baselines3.common.monitor.load_results`` reads it, and so does `read_monitor`.

The file is a log, appended to (and flushed) at the end of every episode while training runs, so
that it can be watched; a crash may leave a partial last line. A resumed run first rewrites it
(atomically) with exactly the episodes finished before its checkpoint, then appends: the file
never counts an episode twice. A new file is written whole (its two header lines) and renamed
into place; the file is never opened through a symbolic link at its name (`open_monitor_file`).

**Reading one** (`read_monitor`, as ``bounce-gym curves`` and ``bounce-gym tune`` do) treats it
as untrusted data: it is opened without following a link (`bounce_gym.files.open_no_follow`: a
link, pipe or device at its name is a `ConfigError`) and read as a stream, complete lines about
a mebibyte at a time (never whole), within these bounds, each a `ConfigError` naming the file
(and the line):

* at most `MAX_MONITOR_BYTES` (1 GiB), `MAX_MONITOR_ROWS` episodes (five million) and
  `MAX_MONITOR_COLUMNS` columns (eight), every line at most `MAX_LINE_BYTES` (64 KiB), UTF-8;
* the return ``r``, the time ``t`` and any other column: finite numbers of magnitude at most
  `MAX_MAGNITUDE` (10¹²); ``True``/``False`` read as 1/0;
* the length ``l``: an integer in [1, `MAX_EPISODE_LENGTH`] (10⁹), so that the env steps, their
  running sum, stay exact in float64 (below 2⁵³ at the row cap);
* the outcomes `MONITOR_KEYS` (``is_success``, ``localized``, ``coverage``): in [0, 1].

Its columns are kept as float64 arrays, 8 bytes a value: at the caps 320 MB, twice that while
the chunks are joined.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from collections.abc import Iterator
from operator import itemgetter
from pathlib import Path

import numpy as np

from bounce_gym.documents import parse_document
from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_write, open_no_follow, writing

SUFFIX = ".monitor.csv"
#: The per-episode outcomes the monitor records when the env's ``info`` has them
#: (`baselines.rl.train_env`), each a fraction in [0, 1]: true/false, or the share covered.
MONITOR_KEYS = ("is_success", "localized", "coverage")
#: the largest monitor file read
MAX_MONITOR_BYTES = 1 << 30
#: the most episodes (rows) a monitor file read may hold
MAX_MONITOR_ROWS = 5_000_000
#: the most columns: ``r``, ``l``, ``t`` and up to five outcomes
MAX_MONITOR_COLUMNS = 8
#: the longest line read (bytes, its end included)
MAX_LINE_BYTES = 64 << 10
#: the largest magnitude of a return, a time or any other column but the length and outcomes
MAX_MAGNITUDE = 1e12
#: the longest episode (env steps) a row may record
MAX_EPISODE_LENGTH = 10**9
#: the bytes read at a time
_CHUNK_BYTES = 1 << 20
_BOOLEANS = {"True": 1.0, "False": 0.0}


def open_monitor_file(path: Path, t_start: float, env_id: str, keys: tuple[str, ...],
                      keep_rows: int | None = None) -> MonitorWriter:
    """A writer of SB3's monitor format on ``path`` (for a ``VecMonitor``'s ``results_writer``):
    a new file (``keep_rows`` None), or the first ``keep_rows`` episodes of the existing one,
    appended to. The file is read and appended to without following a symbolic link: a link at
    its name is a `ConfigError`, and nothing is read or written through it."""
    fields = ("r", "l", "t", *keys)
    if keep_rows is None:
        head = io.StringIO()
        head.write(f"#{json.dumps({'t_start': t_start, 'env_id': env_id})}\n")
        csv.DictWriter(head, fieldnames=fields).writeheader()
        atomic_write(path, head.getvalue().encode())
    else:
        _truncate(path, keep_rows)
    return MonitorWriter(path, fields)


class MonitorWriter:
    """Appends one row per finished episode to a monitor file and flushes it (what SB3's
    ``ResultsWriter`` does, but never through a symbolic link at the file's name)."""

    def __init__(self, path: Path, fields: tuple[str, ...]) -> None:
        self.path = path
        with writing(path, "append to"):
            fd = open_no_follow(path, os.O_WRONLY | os.O_APPEND)
        self.file = os.fdopen(fd, "a", newline="\n", encoding="utf-8")
        self.writer = csv.DictWriter(self.file, fieldnames=fields)

    def write_row(self, episode: dict[str, float]) -> None:
        """Append the episode's row (a failed write is `bounce_gym.errors.OutputError`)."""
        with writing(self.path, "append to"):
            self.writer.writerow(episode)
            self.file.flush()

    def close(self) -> None:
        with writing(self.path, "append to"):
            self.file.close()


def _truncate(path: Path, rows: int) -> None:
    try:
        with os.fdopen(open_no_follow(path, os.O_RDONLY), encoding="utf-8") as fh:
            lines = fh.read().splitlines(keepends=True)
    except FileNotFoundError:
        lines = []
    complete = [line for line in lines[2:] if line.endswith("\n")]
    if len(lines) < 2 or len(complete) < rows:
        raise ConfigError(f"config.resume: the monitor file {path} holds "
                          f"{max(len(complete), 0)} episodes, but the checkpoint was taken after "
                          f"{rows}; restore the file or train without --resume")
    atomic_write(path, "".join(lines[:2] + complete[:rows]).encode())


def read_monitor(path: Path) -> dict[str, np.ndarray]:
    """The columns of a monitor file as float arrays (``True``/``False`` as 1/0), plus
    ``steps``: the env steps of the run when each episode ended, counted as SB3's plots count
    them (the cumulative sum of the lengths). A partial last line is left out. The file is read
    as untrusted data (not through a link, as a stream, every value bounded: the module's
    docstring); a `ConfigError` naming it says what is wrong."""
    what = f"monitor file {path}"
    try:
        fd = open_no_follow(path, os.O_RDONLY)
    except ConfigError as exc:
        raise ConfigError(f"monitor file {exc}") from None
    except OSError as exc:
        raise ConfigError(f"{what}: cannot be read ({exc.strerror or exc})") from None
    with os.fdopen(fd, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        if size > MAX_MONITOR_BYTES:
            raise ConfigError(f"{what}: {size} bytes, more than the {MAX_MONITOR_BYTES} a "
                              "monitor file may hold")
        reader = _Reader(what)
        for number, lines in _chunks(fh, what):
            reader.add(number, lines)
        return reader.columns()


def _chunks(fh, what: str) -> Iterator[tuple[int, list[str]]]:
    """The complete lines of the binary file ``fh``, decoded, about `_CHUNK_BYTES` at a time,
    each list with the number of its first line (from 1). A partial last line is left out; a
    line longer than `MAX_LINE_BYTES`, or bytes that are not UTF-8, are refused."""
    carry = b""
    number = offset = 0
    while block := fh.read(_CHUNK_BYTES):
        data = carry + block
        end = data.rfind(b"\n") + 1
        pieces = data[:end].split(b"\n")[:-1]
        carry = data[end:]
        if len(carry) > MAX_LINE_BYTES or (pieces and max(map(len, pieces)) >= MAX_LINE_BYTES):
            long = next((k for k, piece in enumerate(pieces) if len(piece) >= MAX_LINE_BYTES),
                        len(pieces))
            raise ConfigError(f"{what}: line {number + long + 1} is longer than the "
                              f"{MAX_LINE_BYTES} bytes a line may hold")
        if not pieces:
            continue
        try:
            text = data[:end].decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ConfigError(f"{what}: not UTF-8 text (byte {offset + exc.start})") from None
        lines = text.split("\n")[:-1]
        yield number + 1, lines
        number += len(lines)
        offset += end
    # what is left in ``carry`` is a partial last line (a crash mid-write): left out


class _Reader:
    """The rows of a monitor file, added a chunk of lines at a time (`read_monitor`): the
    first line, the header of column names, then rows, each column parsed and checked against
    its bounds (`_bounds`) as a whole chunk."""

    def __init__(self, what: str) -> None:
        self.what = what
        self.head: list[str] = []
        self.names: list[str] = []
        self.parts: list[list[np.ndarray]] = []
        self.rows = 0

    def add(self, number: int, lines: list[str]) -> None:
        if len(self.head) < 2:
            taken = lines[:2 - len(self.head)]
            self.head += taken
            number, lines = number + len(taken), lines[len(taken):]
            if len(self.head) == 2:
                self._header()
        if lines:
            self._rows(number, lines)

    def _header(self) -> None:
        what = self.what
        first = self.head[0] if self.head else ""
        if not first.startswith("#"):
            raise ConfigError(f"{what}: expected a first line '#{{...}}' (SB3's monitor format)")
        parse_document(f"{what}: its first line", first[1:].encode(), fmt="json")
        names = next(csv.reader(self.head[1:2]), []) if len(self.head) > 1 else []
        if len(names) > MAX_MONITOR_COLUMNS or len(set(names)) != len(names):
            raise ConfigError(f"{what}: expected at most {MAX_MONITOR_COLUMNS} columns, none "
                              f"twice, got {len(names)}")
        if not {"r", "l", "t"} <= set(names):
            raise ConfigError(f"{what}: expected the columns r, l, t")
        self.names = names
        self.parts = [[] for _ in names]

    def _rows(self, number: int, lines: list[str]) -> None:
        what = self.what
        try:
            rows = list(csv.reader(lines))
        except csv.Error as exc:
            raise ConfigError(f"{what}: lines {number} to {number + len(lines) - 1}: not CSV "
                              f"({exc})") from None
        if len(rows) != len(lines):
            raise ConfigError(f"{what}: lines {number} to {number + len(lines) - 1}: a quoted "
                              "value spans lines")
        numbers = range(number, number + len(lines))
        if [] in rows:  # blank lines are left out
            kept = [(n, row) for n, row in zip(numbers, rows, strict=True) if row]
            numbers, rows = [n for n, _ in kept], [row for _, row in kept]
        self.rows += len(rows)
        if self.rows > MAX_MONITOR_ROWS:
            raise ConfigError(f"{what}: holds more than the {MAX_MONITOR_ROWS} episodes a "
                              "monitor file may")
        width = len(self.names)
        if set(map(len, rows)) - {width}:
            k = next(k for k, row in enumerate(rows) if len(row) != width)
            raise ConfigError(f"{what}: line {numbers[k]} holds {len(rows[k])} values, its "
                              f"header {width}")
        if not rows:
            return
        for k, (name, part) in enumerate(zip(self.names, self.parts, strict=True)):
            part.append(self._column(name, list(map(itemgetter(k), rows)), numbers))

    def _column(self, name: str, values: list[str], numbers) -> np.ndarray:
        """One column of a chunk as float64, every value within its bounds."""
        low, high, integer = _bounds(name)
        try:
            parsed = np.fromiter(map(_BOOLEANS.__getitem__ if name in MONITOR_KEYS else float,
                                     values), np.float64, len(values))
        except (KeyError, ValueError):  # numbers as outcomes, booleans or junk elsewhere
            parsed = np.fromiter(map(_number, values), np.float64, len(values))
        with np.errstate(invalid="ignore"):
            good = (parsed >= low) & (parsed <= high)
            if integer:
                good &= parsed == np.floor(parsed)
        if not good.all():
            k = int(np.argmin(good))
            kind = "an integer" if integer else "a number"
            raise ConfigError(f"{self.what}: line {numbers[k]}: column {name} holds "
                              f"{values[k][:40]!r}, not {kind} in [{low:g}, {high:g}]")
        return parsed

    def columns(self) -> dict[str, np.ndarray]:
        if len(self.head) < 2:
            self._header()  # refuses the file: it has no header line
        out = {name: np.concatenate(part) if part else np.zeros(0)
               for name, part in zip(self.names, self.parts, strict=True)}
        out["steps"] = np.cumsum(out["l"])
        return out


def _bounds(name: str) -> tuple[float, float, bool]:
    """The smallest and largest value of the column ``name``, and whether it is an integer."""
    if name == "l":
        return 1.0, float(MAX_EPISODE_LENGTH), True
    if name in MONITOR_KEYS:
        return 0.0, 1.0, False
    return -MAX_MAGNITUDE, MAX_MAGNITUDE, False


def _number(value: str) -> float:
    """``value`` as a float (``True``/``False`` as 1/0); NaN, which no bound admits, for
    anything that is not a number."""
    if value in _BOOLEANS:
        return _BOOLEANS[value]
    try:
        return float(value)
    except ValueError:
        return math.nan
