"""The model files of the JAX learners: weights only, as data.

A file (named and saved like every model, `baselines.rl.model_files`: atomically, its sha256 in
the folder's manifest) is a zip of two entries: ``weights.npz`` (`WEIGHTS_ENTRY`: one array per
layer, ``<net>.<k>.w`` and ``<net>.<k>.b``) and ``bounce_gym.json`` (the training configuration
and ``{"jax": {"num_timesteps": ...}}``). Reading it unpickles nothing, and nothing is inflated
before its size is known to fit the network its configuration describes (`read_weights`): the
``.npz`` entry may hold at most the bytes of that network's arrays plus `WEIGHTS_SLACK` and
`MEMBER_SLACK` per array; it must hold exactly one member ``<name>.npy`` per array; each
member's ``.npy`` header (at most `MAX_NPY_HEADER_BYTES`, read from the member's stream without
its data) must declare exactly the array's shape and float32, and the member's uncompressed
size must be exactly its header and those bytes. Only then is its data read.
"""

from __future__ import annotations

import io
import math
import struct
import zipfile

import numpy as np
from numpy.lib import format as npy

from baselines.rl.model_files import (
    WEIGHTS_ENTRY,
    ZIP_ERRORS,
    ModelFile,
    check_compression,
    read_entry,
)
from baselines.rl.train_config import validate_train_config
from bounce_gym.errors import ConfigError

#: The most bytes of the arrays of a network (its configuration is the file's own).
MAX_WEIGHTS_BYTES = 1 << 30
#: The weights entry (uncompressed) may hold the bytes of its network's arrays plus this, and
#: `MEMBER_SLACK` per array (zip records, deflate's worst-case growth).
WEIGHTS_SLACK = 1 << 20
#: The most bytes of an array's ``.npy`` header (numpy's own default limit, 10,000).
MAX_NPY_HEADER_BYTES = 10_000
#: The bytes an array's member may take in the entry besides its data.
MEMBER_SLACK = 16 << 10
#: The magic string, version and header length that precede an ``.npy`` header.
_NPY_PREFIX_BYTES = 12
#: How each ``.npy`` version read here writes its header's length.
_HEADER_LENGTHS = {(1, 0): "<H", (2, 0): "<I"}
_READ_ERRORS = (*ZIP_ERRORS, ValueError, KeyError, OSError)


class WeightsArchive:
    """Named arrays as what `baselines.rl.model_files.save_model` saves: ``save(fh)`` writes a
    zip holding `WEIGHTS_ENTRY`."""

    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        self.arrays = arrays

    def save(self, fh) -> None:
        buffer = io.BytesIO()
        np.savez(buffer, **self.arrays)
        with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            archive.writestr(WEIGHTS_ENTRY, buffer.getvalue())


def saved_config(trained: ModelFile) -> dict:
    """The validated training configuration the file carries."""
    saved = trained.metadata.get("config")
    if not isinstance(saved, dict):
        raise ConfigError(f"model {trained.path}: carries no training configuration")
    # defaults of None are filled in again, the hyperparameter file was merged already, and
    # vec_env is a default a JAX configuration may not set itself
    config = {k: v for k, v in saved.items()
              if v is not None and k not in ("hyperparams_file", "vec_env")}
    if config.get("algo") != trained.algo:
        raise ConfigError(f"model {trained.path}: its name says {trained.algo}, but its "
                          f"configuration says algo {config.get('algo')!r}")
    try:
        return validate_train_config(config)
    except ConfigError as exc:
        raise ConfigError(f"model {trained.path}: the training configuration it carries is not "
                          f"valid ({exc})") from None


def read_weights(trained: ModelFile, shapes: dict[str, tuple[int, ...]]) -> dict[str, np.ndarray]:
    """The arrays of the file's `WEIGHTS_ENTRY`, which must be exactly ``shapes`` (name ->
    shape), float32. Every size is checked against ``shapes`` before anything is inflated past
    it — the entry's, then each member's and its ``.npy`` header (read from the member's stream,
    without its data) — and only then is any array read; a `ConfigError` naming the file says
    what does not fit."""
    total = sum(_nbytes(shape) for shape in shapes.values())
    if total > MAX_WEIGHTS_BYTES:
        raise ConfigError(f"model {trained.path}: its network needs {total} bytes of weights, "
                          f"more than the {MAX_WEIGHTS_BYTES} a model's may hold")
    limit = total + MEMBER_SLACK * len(shapes) + WEIGHTS_SLACK
    if trained.sizes[WEIGHTS_ENTRY] > limit:
        raise ConfigError(f"model {trained.path}: its entry {WEIGHTS_ENTRY!r} holds "
                          f"{trained.sizes[WEIGHTS_ENTRY]} bytes, more than the {limit} the "
                          "weights of its network may")
    try:
        with zipfile.ZipFile(io.BytesIO(trained.data)) as archive:
            raw = read_entry(archive, WEIGHTS_ENTRY)  # at most `limit` bytes
        with zipfile.ZipFile(io.BytesIO(raw)) as npz:
            members = _members(trained, npz, shapes)
            headers = {name: _header(trained, npz, info, name, shapes[name])
                       for name, info in members.items()}
            return {name: _array(npz, members[name], shapes[name], *header)
                    for name, header in headers.items()}
    except ConfigError:
        raise
    except _READ_ERRORS as exc:
        raise ConfigError(f"model {trained.path}: its weights cannot be read "
                          f"({type(exc).__name__}: {str(exc)[:200]})") from None


def _nbytes(shape: tuple[int, ...]) -> int:
    """The bytes of a float32 array of ``shape``."""
    return 4 * math.prod(shape)


def _members(trained: ModelFile, npz: zipfile.ZipFile,
             shapes: dict[str, tuple[int, ...]]) -> dict[str, zipfile.ZipInfo]:
    """The ``.npz``'s member of each array, by array name: one ``<name>.npy`` per array of
    ``shapes``, none twice, nothing else."""
    infos = npz.infolist()
    names = [info.filename.removesuffix(".npy") for info in infos]
    if sorted(names) != sorted(shapes):
        shown = sorted(names)[:20] + (["..."] if len(names) > 20 else [])
        raise ConfigError(f"model {trained.path}: holds weights {shown}, but its network has "
                          f"{sorted(shapes)} (train with the same env_kwargs)")
    return dict(zip(names, infos, strict=True))


def _header(trained: ModelFile, npz: zipfile.ZipFile, info: zipfile.ZipInfo, name: str,
            shape: tuple[int, ...]) -> tuple[int, bool]:
    """Where the data of one member starts, and whether it is in Fortran order, once the
    member's compression, its uncompressed size and its ``.npy`` header (read from its stream:
    nothing of the data is inflated) are found to be exactly those of a float32 array of
    ``shape``."""
    check_compression(info, f"model {trained.path}: its weights' member")
    nbytes = _nbytes(shape)
    if info.file_size > _NPY_PREFIX_BYTES + MAX_NPY_HEADER_BYTES + nbytes:
        raise ConfigError(f"model {trained.path}: its weights {name!r} take {info.file_size} "
                          f"bytes uncompressed, more than a float32{list(shape)} array, what the "
                          "network needs, may with its .npy header (train with the same "
                          "env_kwargs)")
    with npz.open(info) as member:  # a few small reads: nothing is inflated past them
        version = npy.read_magic(member)
        if version not in _HEADER_LENGTHS:
            raise ConfigError(f"model {trained.path}: its weights {name!r} are an .npy file "
                              f"of version {version}, not 1.0 or 2.0")
        form = _HEADER_LENGTHS[version]
        length = member.read(struct.calcsize(form))
        size = struct.unpack(form, length)[0] if len(length) == struct.calcsize(form) else -1
        if not 0 <= size <= MAX_NPY_HEADER_BYTES:
            raise ConfigError(f"model {trained.path}: its weights {name!r} have an .npy header "
                              f"of {size} bytes, not at most {MAX_NPY_HEADER_BYTES}")
        text = member.read(size)
    read_header = (npy.read_array_header_1_0 if version == (1, 0)
                   else npy.read_array_header_2_0)
    declared, fortran, dtype = read_header(io.BytesIO(length + text),
                                           max_header_size=MAX_NPY_HEADER_BYTES)
    start = npy.MAGIC_LEN + len(length) + len(text)
    if declared != shape or dtype != np.float32:
        raise ConfigError(f"model {trained.path}: its weights {name!r} are "
                          f"{_described(dtype, declared)}, the network needs "
                          f"float32{list(shape)} (train with the same env_kwargs)")
    if info.file_size != start + nbytes:
        raise ConfigError(f"model {trained.path}: its weights {name!r} take {info.file_size} "
                          f"bytes uncompressed, but a float32{list(shape)} array with its .npy "
                          f"header takes {start + nbytes}")
    return start, fortran


def _array(npz: zipfile.ZipFile, info: zipfile.ZipInfo, shape: tuple[int, ...], start: int,
           fortran: bool) -> np.ndarray:
    """The data of a member `_header` checked (exactly its declared size is inflated, and its
    CRC checked)."""
    data = read_entry(npz, info)[start:]
    array = np.frombuffer(data, dtype=np.float32, count=_nbytes(shape) // 4)
    return array.reshape(shape, order="F" if fortran else "C").copy()


def _described(dtype: np.dtype, shape: tuple) -> str:
    """``<dtype>[<shape>]`` as an error message shows a header's claim (at most 80 characters)."""
    text = f"{dtype}{list(shape)}"
    return text if len(text) <= 80 else text[:77] + "..."
