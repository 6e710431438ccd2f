"""The on-disk cache of models estimated from a simulator: one ``.npz`` file per model.

The sampled generalized cell mappings (`bounce_gym.dynamics.sampled_model`,
`bounce_gym.envs.drifters.model_cache`) take seconds to minutes to build, so each is kept in
``<cache>/<kind>/<fingerprint>.npz``, where ``<cache>`` is ``$BOUNCE_GYM_CACHE`` if set (an
absolute path; ``~`` expanded) and ``<home>/cache`` otherwise (``home`` is `bounce_gym.trust.home`).
The fingerprint is the sha256 of everything that defines the model, computed by its owner. Point
``BOUNCE_GYM_CACHE`` at one folder to share built models between users' homes, the machines of a
cluster on a shared file system, or the workers of a test run.

An owner gets its model through `cached`: a model that is missing is built and stored while
holding an exclusive lock on its file (`bounce_gym.files.locked`), and looked up once more under
the lock first, so that processes asking for the same model at once (the workers of a sweep or of
a test run) build it once and the others read what the first stored. A model that is there is
read without the lock, so a read-only cache folder still serves.

A file holds the model's arrays and a JSON header (a ``uint8`` array named ``header``) carrying
at least ``format`` and ``fingerprint``. It is written atomically (`bounce_gym.files.atomic_file`:
a crash leaves no file that looks complete) and read as data only: ``allow_pickle=False``, the
header through `bounce_gym.documents.parse_document`, at most `MAX_BYTES`. A file that is
missing, unreadable, of another format or for another fingerprint is not used: `load_cached` returns
None (with a warning when a file was there) and the owner rebuilds and stores the model again.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np
from gymnasium import logger

from bounce_gym.documents import parse_document
from bounce_gym.errors import BounceGymError, ConfigError
from bounce_gym.files import atomic_file, locked
from bounce_gym.trust import folder_variable, home

__all__ = ["CACHE_VARIABLE", "MAX_BYTES", "cache_folder", "cached", "load_cached", "store"]

#: the environment variable naming the folder of cached models (default ``<home>/cache``)
CACHE_VARIABLE = "BOUNCE_GYM_CACHE"

_Model = TypeVar("_Model")

#: The largest cache file read (bytes); a larger one is rebuilt.
MAX_BYTES = 2 << 30
_HEADER = "header"


def cache_folder(kind: str) -> Path:
    """``<cache>/<kind>``, where the models of one kind are kept (module docstring). A relative
    or unexpandable ``$BOUNCE_GYM_CACHE`` is a `ConfigError`."""
    given = os.environ.get(CACHE_VARIABLE)
    if not given:
        return home() / "cache" / kind
    root = folder_variable(CACHE_VARIABLE, given)
    if not root.is_absolute():
        raise ConfigError(f"{CACHE_VARIABLE}: expected an absolute path, got {given!r}")
    return root / kind


def cached(path: Path, load: Callable[[], _Model | None], build: Callable[[], _Model]) -> _Model:
    """The model kept at ``path``: what ``load()`` returns (None when the file is missing or not
    usable), else, under the file's lock, ``load()`` again or ``build()``, which also stores it
    (module docstring)."""
    found = load()
    if found is not None:
        return found
    with locked(path):
        found = load()
        return found if found is not None else build()


def store(path: Path, header: dict, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` and the JSON ``header`` (with ``format`` and ``fingerprint``) to
    ``path`` atomically, creating its folder."""
    if _HEADER in arrays:
        raise ValueError(f"an array may not be named {_HEADER!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(header, sort_keys=True).encode()
    with atomic_file(path) as fh:
        np.savez(fh, **arrays, **{_HEADER: np.frombuffer(text, dtype=np.uint8)})


def load_cached(path: Path, fmt: int, key: str) -> tuple[dict, dict[str, np.ndarray]] | None:
    """The header and arrays stored at ``path`` when it holds the model of format ``fmt`` and
    fingerprint ``key``; None when the file is missing or not usable (then a warning says why,
    and the caller rebuilds the model). The owner still checks the arrays' content."""
    if not path.is_file():
        return None
    try:
        if path.stat().st_size > MAX_BYTES:
            raise ValueError(f"larger than {MAX_BYTES} bytes")
        with np.load(io.BytesIO(path.read_bytes()), allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in npz.files}
        raw = arrays.pop(_HEADER, None)
        if raw is None or raw.dtype != np.uint8:
            raise ValueError("it has no header")
        header = parse_document(str(path), raw.tobytes(), fmt="json")
        if not isinstance(header, dict) or header.get("format") != fmt \
                or header.get("fingerprint") != key:
            raise ValueError("its header does not match the model asked for")
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile,
            BounceGymError) as exc:
        warn_unusable(path, exc)
        return None
    return header, arrays


def warn_unusable(path: Path, problem: object) -> None:
    """Say that the cached model at ``path`` is rebuilt, and why."""
    logger.warn(f"the cached model {path} is unusable ({problem}); rebuilding it")
