"""Per-episode monitor files: SB3's ``monitor.csv`` format, one per training run.

``models/<name>/<run>_seed<seed>.monitor.csv`` holds a first line ``#{"t_start": ..., "env_id":
...}``, a header ``r,l,t[,<outcome>...]`` and one row per finished episode in the order they
finished: return ``r`` (the env's own reward, before any normalisation), length ``l`` (env
steps), wall-clock seconds ``t`` since the run started, and the task's outcome keys the env
reports (``is_success``, ``localized``, ``coverage``; `baselines.rl.train_env.MONITOR_KEYS`). SB3's
``stable_baselines3.common.monitor.load_results`` reads it, and so does `read_monitor`.

The file is a log, appended to (and flushed) at the end of every episode while training runs, so
that it can be watched; a crash may leave a partial last line. A resumed run first rewrites it
(atomically) with exactly the episodes finished before its checkpoint, then appends: the file
never counts an episode twice. A new file is written whole (its two header lines) and renamed
into place; the file is never opened through a symbolic link at its name (`open_monitor_file`).
"""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path

import numpy as np

from bounce_gym.documents import parse_document
from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_write, open_no_follow, writing

SUFFIX = ".monitor.csv"
#: the largest monitor file read (about ten million episodes)
MAX_MONITOR_BYTES = 1 << 30


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
    them (the cumulative sum of the lengths). A partial last line is left out."""
    size = path.stat().st_size
    if size > MAX_MONITOR_BYTES:
        raise ConfigError(f"monitor file {path}: {size} bytes, more than the {MAX_MONITOR_BYTES} "
                          "a monitor file may hold")
    try:
        lines = path.read_bytes().decode("utf-8").splitlines(keepends=True)
    except UnicodeDecodeError as exc:
        raise ConfigError(f"monitor file {path}: not UTF-8 text (byte {exc.start})") from None
    if not lines or not lines[0].startswith("#"):
        raise ConfigError(f"monitor file {path}: expected a first line '#{{...}}' (SB3's "
                          "monitor format)")
    parse_document(f"monitor file {path}: its first line", lines[0][1:].encode(), fmt="json")
    body = [line for line in lines[1:] if line.endswith("\n")]
    reader = csv.DictReader(io.StringIO("".join(body)))
    columns: dict[str, list[float]] = {name: [] for name in reader.fieldnames or []}
    if not {"r", "l", "t"} <= set(columns):
        raise ConfigError(f"monitor file {path}: expected the columns r, l, t")
    for row in reader:
        for name, value in row.items():
            columns[name].append(_number(path, name, value))
    out = {name: np.asarray(values, dtype=np.float64) for name, values in columns.items()}
    out["steps"] = np.cumsum(out["l"])
    return out


def _number(path: Path, name: str, value: str) -> float:
    if value in ("True", "False"):
        return float(value == "True")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"monitor file {path}: column {name} holds {value!r}, not a "
                          "number") from None
