"""Trust that comes from outside the folders the package reads: a secret key and a list of
trusted file digests, both in this user's own bounce_gym folder.

Most files the package reads are plain data (JSON, CSV, NumPy arrays, a model's weights read
with ``torch.load(weights_only=True)``), and their content decides nothing about what runs. A
few hold Python objects that only pickle can write back — the finished units of an evaluation
sweep, the state of a training run caught mid-episode in a checkpoint — and unpickling runs
whatever the file says. Such a file is read only when this module vouches for it:

* **signed**: the package signed the bytes when it wrote them, with an HMAC-SHA256 under the
  user's secret key (`sign`, `verify`). A file planted in a results or models folder by anyone
  who does not hold the key fails the check;
* **trusted by digest**: the user listed the file's sha256 on purpose (``bounce-gym trust FILE``,
  `add_trusted`), e.g. a checkpoint received from a colleague.

Both live in the user's bounce_gym folder (`home`), never in the folder being read: a folder an
attacker supplies cannot vouch for itself. The folder is ``$BOUNCE_GYM_HOME`` if set (``~`` and
``~user`` expanded), else ``$XDG_CONFIG_HOME/bounce_gym`` if that is an absolute path (a relative
one is ignored, as the XDG Base Directory specification says), else ``~/.config/bounce_gym``;
the key is created there on first use (32 random bytes, readable by the user only). Machines of
a cluster that should accept each other's files share the folder (or the same key file).

**What is trusted, checked as ssh checks its keys.** Whoever can write into the folder can plant
a key that signs a pickle, or a digest that vouches for one, so before the key or the digest
list is read (`secret_key`, `trusted_digests`, `add_trusted`):

* the folder (links followed: where it lies is the user's choice) must belong to this user (or
  to root) and must not be writable by its group or by others (``chmod go-w``);
* the key must be a regular file — opened with ``O_NOFOLLOW | O_NONBLOCK`` inside the checked
  folder and checked on the open descriptor (``fstat``), so a link, a pipe (whose read would
  wait for ever) or a device planted at its name is refused unread — that belongs to this user
  (or root) and that neither its group nor others may read or write (mode 0600 or stricter:
  ``chmod 600``);
* the digest list likewise, except that others may read it (it holds no secret).

Each refusal is one `ConfigError` line naming the file and the command that fixes it.
"""

from __future__ import annotations

import errno
import hashlib
import hmac
import json
import os
import secrets
import stat
from pathlib import Path

from bounce_gym.documents import Limits, parse_document
from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_write, check_path_text, locked

#: the environment variable naming the user's bounce_gym folder
HOME_VARIABLE = "BOUNCE_GYM_HOME"
#: the XDG Base Directory variable of the user's configuration folders (used when absolute)
XDG_VARIABLE = "XDG_CONFIG_HOME"
KEY_FILE = "secret.key"
TRUSTED_FILE = "trusted.json"
_KEY_BYTES = 32


def folder_variable(variable: str, given: str) -> Path:
    """The folder that the environment variable ``variable`` names (its value ``given``), ``~``
    and ``~user`` expanded; a NUL character or a ``~user`` that names no user is a
    `ConfigError` naming the variable."""
    check_path_text(variable, given)
    try:
        return Path(given).expanduser()
    except RuntimeError:  # ~nosuchuser, or ~ without $HOME nor a password entry
        raise ConfigError(f"{variable}: cannot expand {given!r}: no such user or home folder; "
                          "give the folder's absolute path") from None


def home() -> Path:
    """The user's bounce_gym folder (module docstring); not created here. A ``~user`` that
    names no user, or a home folder that cannot be found, is a `ConfigError`."""
    given = os.environ.get(HOME_VARIABLE)
    if given:
        return folder_variable(HOME_VARIABLE, given)
    config = os.environ.get(XDG_VARIABLE, "")
    if os.path.isabs(config):  # the XDG spec: a relative value is invalid and ignored
        check_path_text(XDG_VARIABLE, config)
        return Path(config) / "bounce_gym"
    try:
        return Path.home() / ".config" / "bounce_gym"
    except RuntimeError:
        raise ConfigError(f"{HOME_VARIABLE}: not set, and your home folder cannot be found "
                          "($HOME is not set); set it to the folder for your key") from None


def is_mine(uid: int) -> bool:
    """Whether a file of owner ``uid`` may be trusted: this user's (or root's, as ssh has it)."""
    return uid in (os.geteuid(), 0)


def _open_folder(what: str, create: bool = True) -> tuple[Path, int]:
    """The user's folder and a descriptor of it, after checking that only its owner — this
    user or root — can write into it (module docstring); ``create``: make it (mode 0700) if it
    is missing, else a missing folder raises `FileNotFoundError`. ``what`` names the file
    sought, in errors."""
    folder = home()
    try:
        if create:
            folder.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except FileNotFoundError:
        if not create:
            raise
        raise ConfigError(f"{HOME_VARIABLE}: cannot read or create {what} in {folder} "
                          "(a folder above it vanished)") from None
    except OSError as exc:
        raise ConfigError(f"{HOME_VARIABLE}: cannot read or create {what} in {folder} "
                          f"({exc.strerror or exc})") from None
    info = os.fstat(fd)
    problem = None
    if not is_mine(info.st_uid):
        problem = (f"the folder {folder} belongs to another user (uid {info.st_uid}), whose "
                   "key and trusted digests are not yours to trust; use a folder of your own")
    elif info.st_mode & 0o022:
        problem = (f"the folder {folder} can be written by others (mode "
                   f"{stat.S_IMODE(info.st_mode):04o}), who could plant a key or trusted "
                   f"digests there; chmod go-w {folder}")
    if problem is not None:
        os.close(fd)
        raise ConfigError(f"{HOME_VARIABLE}: {problem}")
    return folder, fd


def _open_checked(folder: int, path: Path, flags: int, label: str, secret: bool) -> int:
    """A descriptor of the regular file ``path`` (its name in the folder of descriptor
    ``folder``; ``label`` names it in errors), opened without following a link and without
    blocking; raises `ConfigError` unless it is a regular file of this user (or root) that
    others cannot write (``secret``: nor read). `FileNotFoundError` passes through."""
    try:
        fd = os.open(path.name, flags | os.O_NOFOLLOW | os.O_NONBLOCK, dir_fd=folder)
    except FileNotFoundError:
        raise
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise ConfigError(f"{HOME_VARIABLE}: cannot read or create {label}: it is a "
                              "symbolic link, which is not followed; remove it") from None
        raise ConfigError(f"{HOME_VARIABLE}: cannot read or create {label} "
                          f"({exc.strerror or exc})") from None
    info = os.fstat(fd)
    mode = stat.S_IMODE(info.st_mode)
    problem = None
    if not stat.S_ISREG(info.st_mode):
        problem = f"{label} is not a regular file; remove it"
    elif not is_mine(info.st_uid):
        problem = (f"{label} belongs to another user (uid {info.st_uid}); remove it, or make it "
                   f"yours (chown)")
    elif secret and mode & 0o077:
        problem = (f"{label} can be read or written by others (mode {mode:04o}); "
                   f"chmod 600 {path}")
    elif mode & 0o022:
        problem = f"{label} can be written by others (mode {mode:04o}); chmod go-w {path}"
    if problem is not None:
        os.close(fd)
        raise ConfigError(f"{HOME_VARIABLE}: {problem}")
    return fd


def secret_key() -> bytes:
    """The user's secret key, created on first use (exclusively, readable by the user only),
    read after the checks of the module docstring."""
    folder, dirfd = _open_folder("the key")
    path = folder / KEY_FILE
    try:
        try:
            fd = os.open(KEY_FILE, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600,
                         dir_fd=dirfd)
        except FileExistsError:
            pass
        else:
            with os.fdopen(fd, "wb") as fh:
                fh.write(secrets.token_bytes(_KEY_BYTES))
                fh.flush()
                os.fsync(fh.fileno())
        fd = _open_checked(dirfd, path, os.O_RDONLY, f"the key {path}", secret=True)
        with os.fdopen(fd, "rb") as fh:
            key = fh.read(_KEY_BYTES + 1)
    except FileNotFoundError:
        raise ConfigError(f"{HOME_VARIABLE}: cannot read or create the key {path} (it was "
                          "removed meanwhile)") from None
    except OSError as exc:
        raise ConfigError(f"{HOME_VARIABLE}: cannot read or create the key {path} "
                          f"({exc.strerror or exc})") from None
    finally:
        os.close(dirfd)
    if len(key) != _KEY_BYTES:  # a racing creator has not written it yet, or it is damaged
        raise ConfigError(f"{HOME_VARIABLE}: the key {path} is not {_KEY_BYTES} bytes; delete it "
                          "to have a new one made (files signed with it are then re-made)")
    return key


def sign(data: bytes, purpose: str) -> str:
    """The hex HMAC-SHA256 of ``data`` under the user's key; ``purpose`` (e.g. ``"unit"``)
    keeps a signature of one kind of file from passing for another kind."""
    return hmac.new(secret_key(), purpose.encode() + b"\0" + data, hashlib.sha256).hexdigest()


def verify(data: bytes, signature: object, purpose: str) -> bool:
    """Whether ``signature`` is `sign` ``(data, purpose)`` (compared in constant time; a
    signature read from a file may hold anything, which is no signature)."""
    return isinstance(signature, str) and signature.isascii() \
        and hmac.compare_digest(sign(data, purpose), signature)


def digest(data: bytes) -> str:
    """The hex sha256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def trusted_digests() -> frozenset[str]:
    """The sha256 digests the user has trusted (`add_trusted`), read after the checks of the
    module docstring."""
    try:
        folder, dirfd = _open_folder("the trusted digests", create=False)
    except FileNotFoundError:
        return frozenset()
    path = folder / TRUSTED_FILE
    limits = Limits()
    try:
        fd = _open_checked(dirfd, path, os.O_RDONLY, str(path), secret=False)
        with os.fdopen(fd, "rb") as fh:
            data = fh.read(limits.bytes + 1)
    except FileNotFoundError:
        return frozenset()
    except OSError as exc:
        raise ConfigError(f"{HOME_VARIABLE}: cannot read {path} ({exc.strerror or exc})") from None
    finally:
        os.close(dirfd)
    try:
        entries = parse_document(f"{HOME_VARIABLE}: {path}", data, fmt="json", limits=limits)
    except ConfigError as exc:
        raise ConfigError(f"{exc}; delete it and trust the files again") from None
    if not isinstance(entries, list) or not all(isinstance(d, str) for d in entries):
        raise ConfigError(f"{HOME_VARIABLE}: {path} is not a list of sha256 digests")
    return frozenset(entries)


def add_trusted(sha256: str) -> None:
    """Add a digest to the user's trusted ones (under a lock, so concurrent calls lose none)."""
    if len(sha256) != 64 or any(c not in "0123456789abcdef" for c in sha256):
        raise ConfigError(f"trust: expected a sha256 digest (64 hex digits), got {sha256!r}")
    folder, dirfd = _open_folder("the trusted digests")
    os.close(dirfd)
    path = folder / TRUSTED_FILE
    with locked(path):
        entries = sorted(trusted_digests() | {sha256})
        atomic_write(path, (json.dumps(entries, indent=1) + "\n").encode(), mode=0o600)
