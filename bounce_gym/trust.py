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
attacker supplies cannot vouch for itself. The folder is ``$BOUNCE_GYM_HOME`` if set, else
``$XDG_CONFIG_HOME/bounce_gym``, else ``~/.config/bounce_gym``; the key is created there on first
use (32 random bytes, readable by the user only). Machines of a cluster that should accept each
other's files share the folder (or the same key file).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import secrets
from pathlib import Path

from bounce_gym.documents import read_document
from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_write, locked

#: the environment variable naming the user's bounce_gym folder
HOME_VARIABLE = "BOUNCE_GYM_HOME"
KEY_FILE = "secret.key"
TRUSTED_FILE = "trusted.json"
_KEY_BYTES = 32


def home() -> Path:
    """The user's bounce_gym folder (module docstring); not created here."""
    given = os.environ.get(HOME_VARIABLE)
    if given:
        return Path(given).expanduser()
    config = os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config"
    return Path(config) / "bounce_gym"


def secret_key() -> bytes:
    """The user's secret key, created on first use (exclusively, readable by the user only)."""
    path = home() / KEY_FILE
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        except FileExistsError:
            pass
        else:
            with os.fdopen(fd, "wb") as fh:
                fh.write(secrets.token_bytes(_KEY_BYTES))
                fh.flush()
                os.fsync(fh.fileno())
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
        with os.fdopen(fd, "rb") as fh:
            key = fh.read(_KEY_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"{HOME_VARIABLE}: cannot read or create the key {path} "
                          f"({exc.strerror or exc})") from None
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


def _trusted_path() -> Path:
    return home() / TRUSTED_FILE


def trusted_digests() -> frozenset[str]:
    """The sha256 digests the user has trusted (`add_trusted`)."""
    path = _trusted_path()
    if not path.exists():
        return frozenset()
    try:
        entries = read_document(path, HOME_VARIABLE, fmt="json")
    except ConfigError as exc:
        raise ConfigError(f"{exc}; delete it and trust the files again") from None
    if not isinstance(entries, list) or not all(isinstance(d, str) for d in entries):
        raise ConfigError(f"{HOME_VARIABLE}: {path} is not a list of sha256 digests")
    return frozenset(entries)


def add_trusted(sha256: str) -> None:
    """Add a digest to the user's trusted ones (under a lock, so concurrent calls lose none)."""
    if len(sha256) != 64 or any(c not in "0123456789abcdef" for c in sha256):
        raise ConfigError(f"trust: expected a sha256 digest (64 hex digits), got {sha256!r}")
    path = _trusted_path()
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    with locked(path):
        entries = sorted(trusted_digests() | {sha256})
        atomic_write(path, (json.dumps(entries, indent=1) + "\n").encode())

