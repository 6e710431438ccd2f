"""Writing files so that readers never see one half-written, updating a shared file from several
processes without losing an update, and checking early that a folder can be written at all."""

from __future__ import annotations

import contextlib
import fcntl
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from bounce_gym.errors import ConfigError


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """A temporary path that becomes ``path`` only once the ``with`` block has finished, for
    writers that need a file name rather than an open file (e.g. a NetCDF library).

    The block writes the file at the yielded path: a hidden name in the same folder
    (``.<name>.<random>.tmp``, created empty). The file is then flushed to disk and renamed over
    ``path``, so a crash at any instant leaves either the old ``path`` or the new one, never a
    partial file under its name; an exception in the block removes the temporary file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:  # the writer may have replaced the file: sync what is there
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes files private; results are not
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    with contextlib.suppress(OSError):  # make the rename itself durable where the OS allows
        folder = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(folder)
        finally:
            os.close(folder)


@contextlib.contextmanager
def atomic_file(path: Path) -> Iterator[BinaryIO]:
    """A binary file (opened for writing and reading) that becomes ``path`` only once the
    ``with`` block has finished (`atomic_path`: a temporary file in the same folder, flushed to
    disk, then renamed over ``path``; an exception in the block removes it)."""
    with atomic_path(path) as tmp, open(tmp, "w+b") as fh:
        yield fh
        fh.flush()


def atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through `atomic_file`."""
    with atomic_file(path) as fh:
        fh.write(data)


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``path`` for the ``with`` block: the processes that read,
    change and rewrite a shared file (e.g. a manifest several training runs add to at once) each
    do it inside ``locked(path)``, so none overwrites another's update. The lock is an advisory
    ``flock`` on the hidden file ``.<name>.lock`` beside ``path`` (POSIX; it also works on
    NFSv4 and most cluster file systems); the kernel drops it when the process dies."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path.parent / f".{path.name}.lock", os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing the descriptor releases the lock


def check_writable(field: str, folder: Path) -> None:
    """Raise `ConfigError` naming ``field`` unless ``folder`` is, or can be created as, a
    folder this process may write into; nothing is created."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ConfigError(f"{field}: cannot write into {str(folder)!r}: {str(existing)!r} is not "
                          "a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        what = "folder" if existing == folder else f"folder {str(existing)!r}"
        raise ConfigError(f"{field}: cannot write into {str(folder)!r}: the {what} is not "
                          "writable")
