"""Writing files so that readers never see one half-written, updating a shared file from several
processes without losing an update, and checking early that a folder can be written at all.

**Names and links.** A name from a configuration that becomes part of a path (a run's name, an
experiment's, a models folder's) is one plain path component (`check_path_component`), so
nothing is written outside the folder the user gave. Inside that folder the package never writes
through a symbolic link someone planted at a name it writes: whole files are written beside
their name and renamed over it (`atomic_file`, `atomic_path`: a link at the name is replaced,
its target untouched), and a file opened in place — a log appended to, a lock file — is opened
without following a link (`open_no_follow`: a link is refused). A folder the user names (an
``output`` that is a link to another disk) is theirs to choose and is followed.

**Faults.** A write that fails — a full disk, a folder that is not writable, a link swapped in
while the file is written — raises `bounce_gym.errors.OutputError`, one line naming the path
and the system's reason (``<path>: cannot write it: No space left on device``), and leaves the
old file, or none, under the path's name: never a partial one. The commands print it as one
``error:`` line.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import shutil
import stat
import tempfile
import unicodedata
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from bounce_gym.errors import ConfigError, OutputError


def output_error(path: Path | str, exc: OSError, what: str = "write") -> OutputError:
    """The package's one-line error for the `OSError` ``exc`` met while writing ``path``
    (``what``: the verb, e.g. ``create``); an `OutputError` is returned as it is."""
    if isinstance(exc, OutputError):
        return exc
    reason = exc.strerror or str(exc) or type(exc).__name__
    if exc.errno == errno.ELOOP:
        reason = f"a symbolic link is in the way, and it is not followed ({reason})"
    return OutputError(f"{path}: cannot {what} it: {reason}", exc.errno)


@contextlib.contextmanager
def writing(path: Path | str, what: str = "write") -> Iterator[None]:
    """Turn an `OSError` raised in the ``with`` block into `output_error` naming ``path``."""
    try:
        yield
    except OSError as exc:
        raise output_error(path, exc, what) from None


@contextlib.contextmanager
def atomic_path(path: Path, mode: int | None = None) -> Iterator[Path]:
    """A temporary path that becomes ``path`` only once the ``with`` block has finished, for
    writers that need a file name rather than an open file (e.g. a NetCDF library).

    The block writes the file at the yielded path: a hidden name in the same folder
    (``.<name>.<random>.tmp``, created empty). The file is then flushed to disk, given
    ``mode`` (default: 0o666 less the umask, as a file created the usual way) and renamed over
    ``path``, so a crash at any instant leaves either the old ``path`` or the new one, never a
    partial file under its name; an exception in the block removes the temporary file. An
    `OSError` on the way — in the block too — is raised as the `OutputError` naming ``path``
    (`output_error`)."""
    path = Path(path)
    with writing(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with open(tmp, "rb+", opener=_no_follow) as fh:  # the writer may have replaced it
            os.fsync(fh.fileno())
        os.chmod(tmp, _usual(0o666) if mode is None else mode)  # mkstemp makes files private
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise output_error(path, exc) from None
        raise
    _fsync(path.parent)  # make the rename itself durable


@contextlib.contextmanager
def atomic_file(path: Path, mode: int | None = None) -> Iterator[BinaryIO]:
    """A binary file (opened for writing and reading) that becomes ``path`` only once the
    ``with`` block has finished (`atomic_path`: a temporary file in the same folder, flushed to
    disk, given ``mode``, then renamed over ``path``; an exception in the block removes it, an
    `OSError` is raised as the `OutputError` naming ``path``)."""
    with atomic_path(path, mode) as tmp, open(tmp, "w+b", opener=_no_follow) as fh:
        yield fh
        fh.flush()


def atomic_write(path: Path, data: bytes, mode: int | None = None) -> None:
    """Write ``data`` to ``path`` through `atomic_file`."""
    with atomic_file(path, mode) as fh:
        fh.write(data)


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``path`` for the ``with`` block: the processes that read,
    change and rewrite a shared file (e.g. a manifest several training runs add to at once) each
    do it inside ``locked(path)``, so none overwrites another's update. The lock is an advisory
    ``flock`` on the hidden file ``.<name>.lock`` beside ``path`` (POSIX; it also works on
    NFSv4 and most cluster file systems); the kernel drops it when the process dies. A link at
    the lock file's name is refused (`open_no_follow`)."""
    path = Path(path)
    lock = path.parent / f".{path.name}.lock"
    with writing(lock, "create"):
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = open_no_follow(lock, os.O_RDWR | os.O_CREAT)
    try:
        with writing(lock, "lock"):
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing the descriptor releases the lock


def _no_follow(path: str, flags: int) -> int:
    """An ``opener`` for `open` that does not follow a symbolic link at ``path``."""
    return os.open(path, flags | os.O_NOFOLLOW, 0o666)


def open_no_follow(path: Path, flags: int) -> int:
    """``os.open(path, flags)`` of a regular file (one it creates gets mode 0o666 less the
    umask), without following a symbolic link: a link at ``path``, or a pipe or device planted
    there (which could block the open or a read for ever), raises `ConfigError` naming the
    file, and nothing is read or written through it."""
    try:
        fd = _no_follow(str(path), flags | os.O_NONBLOCK)
    except OSError as exc:
        if exc.errno == errno.ELOOP or os.path.islink(path):
            raise ConfigError(f"{path}: is a symbolic link; the package does not open its own "
                              "files through one, remove it") from None
        if exc.errno != errno.ENXIO:  # a pipe nobody reads
            raise
        fd = None
    if fd is None or not stat.S_ISREG(os.fstat(fd).st_mode):
        if fd is not None:
            os.close(fd)
        raise ConfigError(f"{path}: is not a regular file; remove it")
    return fd


def refuse_links(field: str, base: Path, path: Path) -> None:
    """Raise `ConfigError` naming ``field`` if ``path``, or a folder between ``base`` and it,
    is a symbolic link (``path`` lies below ``base``; ``base`` itself, the user's choice, may be
    one). For the files and folders the package names itself inside a folder the user gave,
    checked before writing there; what does not exist yet passes."""
    here = Path(base)
    for part in Path(path).relative_to(base).parts:
        here = here / part
        if here.is_symlink():
            raise ConfigError(f"{field}: {here} is a symbolic link; the package does not write "
                              "through a link inside its folders, remove it")


#: the most bytes (UTF-8) of a name that becomes a path component (`check_path_component`),
#: leaving room for what is added to it (``-<timestamp>``, ``-units``, ``-tune``)
MAX_NAME_BYTES = 100


def check_path_component(field: str, name: object, what: str = "a name for files and "
                         "folders") -> None:
    """Raise `ConfigError` naming ``field`` unless ``name`` can be one component of a path as
    it is: a non-empty string of at most `MAX_NAME_BYTES` bytes (UTF-8), without ``/``, ``\\``
    and control characters (NUL, line breaks, …), not starting with ``.`` (``.``, ``..``, hidden
    names) or ``-`` (read as an option by commands), nor starting or ending with a space. ``what``
    says what the name is for."""
    problem = _component_problem(name)
    if problem is not None:
        shown = repr(name) if not isinstance(name, str) or len(name) <= 60 \
            else repr(name[:50]) + "..."
        raise ConfigError(f"{field}: expected {what} (one path component), got {shown}: "
                          f"{problem}")


def _component_problem(name: object) -> str | None:
    if not isinstance(name, str):
        return "it is not a string"
    if not name:
        return "it is empty"
    odd = next((c for c in name if unicodedata.category(c) in ("Cc", "Cf", "Cs", "Zl", "Zp")),
               None)
    if odd is not None:
        return f"it contains the control character U+{ord(odd):04X}"
    for bad in ("/", "\\"):
        if bad in name:
            return f"it contains {bad!r}"
    if name[0] in ".-":
        return f"it starts with {name[0]!r}"
    if name != name.strip():
        return "it starts or ends with a space"
    size = len(name.encode("utf-8"))
    if size > MAX_NAME_BYTES:
        return f"it is {size} bytes long, at most {MAX_NAME_BYTES}"
    return None


class NewFolder:
    """A folder that appears whole or not at all. ``with NewFolder(path) as tmp:`` the block
    writes into ``tmp``, a hidden folder beside ``path``, ``.<name>.tmp-<random>``, private to
    the user while it is written (so nothing can be planted in it). When the block finishes,
    every file in it is flushed to disk, the folder gets the usual permissions and is renamed to
    ``path`` — or, if that name is taken, to ``path-2``, ``path-3``, …: never over an existing
    file or folder; `path` is then the name it got. An exception in the block removes the
    temporary folder; a crash or a kill leaves it, hidden, for whoever cleans up (what collects
    finished folders skips names starting with ``.``)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._tmp: Path | None = None

    def __enter__(self) -> Path:
        with writing(self.path, "create"):
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.tmp-",
                                              dir=self.path.parent))
        return self._tmp

    def __exit__(self, kind, exc, traceback) -> None:
        tmp, self._tmp = self._tmp, None
        assert tmp is not None
        if kind is not None:
            shutil.rmtree(tmp, ignore_errors=True)
            if isinstance(exc, OSError):  # named by the folder it was to become
                message = str(output_error(tmp, exc)).replace(str(tmp), str(self.path))
                raise OutputError(message, exc.errno) from None
            return
        try:
            self.path = _publish(tmp, self.path)
        except BaseException as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            if isinstance(exc, OSError):
                raise output_error(self.path, exc, "create") from None
            raise


def _publish(tmp: Path, path: Path) -> Path:
    """Flush ``tmp``'s files, give it the usual folder permissions and rename it to ``path``
    or the first free ``path-<n>``; returns the name it got."""
    for root, _, files in os.walk(tmp):
        for name in files:
            _fsync(Path(root) / name)
    os.chmod(tmp, _usual(0o777))  # mkdtemp's folder is the user's only
    for n in range(1, 1000):
        target = path if n == 1 else path.with_name(f"{path.name}-{n}")
        if os.path.lexists(target):
            continue
        try:
            os.rename(tmp, target)  # over nothing but, at worst, an empty folder made meanwhile
        except OSError as exc:
            if exc.errno in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR):
                continue  # taken meanwhile
            raise
        _fsync(path.parent)
        return target
    raise ConfigError(f"{path}: 999 folders of this name exist already")


def _usual(mode: int) -> int:
    """``mode`` less this process's umask: the permissions of a file created the usual way."""
    umask = os.umask(0)
    os.umask(umask)
    return mode & ~umask


def _fsync(path: Path) -> None:
    """Flush a file or a folder (its entries) to disk, where the OS allows."""
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def check_path_text(field: str, path: object) -> None:
    """Raise `ConfigError` naming ``field`` if the path ``path`` holds a NUL character, which
    no path can (the operating system would refuse it at its first use)."""
    if "\0" in str(path):
        raise ConfigError(f"{field}: {str(path)!r} contains a NUL character")


def check_writable(field: str, folder: Path) -> None:
    """Raise `ConfigError` naming ``field`` unless ``folder`` is, or can be created as, a
    folder this process may write into; nothing is created."""
    check_path_text(field, folder)
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
