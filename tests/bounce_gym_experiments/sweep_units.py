"""Unit functions for the executor tests, imported by name (the folder's conftest puts this
folder on ``sys.path`` and ``PYTHONPATH``) so that pool and Ray workers find them.

The failures are injected here, in test-only functions wrapping a unit, not in the package: a
marker file makes a unit's worker die (``os._exit``) or raise on its first attempt only."""

from __future__ import annotations

import os
from pathlib import Path


def square(x: int) -> int:
    return x * x


def pid_of(_: int) -> int:
    return os.getpid()


def fail(x: int) -> int:
    raise ValueError(f"unit {x} cannot be done")


def _first_time(marker: Path) -> bool:
    """Whether ``marker`` did not exist yet (it does now)."""
    try:
        Path(marker).touch(exist_ok=False)
    except FileExistsError:
        return False
    return True


def die_once(marker: Path, fn, *args):
    """``fn(*args)``, except that the first call (no ``marker`` yet) kills its process."""
    if _first_time(marker):
        os._exit(1)
    return fn(*args)


def raise_once(marker: Path, fn, *args):
    """``fn(*args)``, except that the first call (no ``marker`` yet) raises."""
    if _first_time(marker):
        raise RuntimeError("injected failure")
    return fn(*args)


def count_calls(folder: Path, fn, *args):
    """``fn(*args)``, leaving one file per call in ``folder`` (how many times units ran)."""
    import tempfile

    Path(folder).mkdir(parents=True, exist_ok=True)
    tempfile.mkstemp(dir=folder)
    return fn(*args)


def die(x: int) -> int:
    """Kill the process running it."""
    os._exit(1)
