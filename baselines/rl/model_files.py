"""Model files: their names, saving them atomically, and reading them as data.

`baselines.rl.train` saves, in ``<models>/<name>/``:

* the model ``<run>_seed<seed>.zip`` (`MODEL_NAME`), where ``<run>`` is the algorithm, optionally
  followed by ``-<variant>`` (``ppo``, ``ppo-stack4``, ``recurrentppo``, ``dqn``); the evaluation
  loads only files with such names, never temporary or partial ones;
* checkpoints ``checkpoints/<run>_seed<seed>_<steps>_steps.zip`` (`CHECKPOINT_NAME`), never
  overwritten.

A JAX learner's file (``jax_ppo``, ``jax_dqn``; `JAX_ALGOS`) and a multi-robot learner's
(``ippo``, ``mappo``; `MARL_ALGOS`, `baselines.rl.marl`) hold no SB3 part: their weights as an
``.npz`` (`WEIGHTS_ENTRY`, read with ``allow_pickle=False`` by `baselines.rl.jaxrl.weights`) and
their `METADATA_ENTRY`, saved and listed in the manifest like the others (`WEIGHTS_ALGOS`).

A model zip is Stable-Baselines3's file plus entries of its own, which SB3 ignores:
``bounce_gym.json`` (`METADATA_ENTRY`: the training configuration, the observation wrappers
the model was trained behind — frame stacking, VecNormalize statistics, `baselines.rl.wrappers`
— so the evaluation rebuilds them, and ``trained_with``, the machine and library versions of
the run, `bounce_gym.provenance`; `ModelFile.trained_with` reads it) and, in a checkpoint, ``bounce_gym_resume.pkl``
(`RESUME_ENTRY`: what resuming needs besides the weights and the optimiser,
`baselines.rl.resume`) with its signature ``bounce_gym_resume.sig`` (`SIGNATURE_ENTRY`). One
file holds a whole checkpoint, so a crash leaves either all of it or none. The format and the
threat model are described in ``docs/model_files.md``.

**Data, not code.** Loading a model never unpickles anything from its file: `read_model` reads
only JSON (after checking every entry's size), and `ModelFile.load` hands Stable-Baselines3 a
replacement, rebuilt by this package, for every object the file would have it unpickle
(`baselines.rl.model_load`); the weights are read with ``torch.load(weights_only=True)``. Only a
checkpoint's resume state stays a pickle, and `ModelFile.resume_state` unpickles it only when it
is vouched for from outside the folder (`bounce_gym.trust`): signed with this user's key when a
run of theirs saved it, or trusted by its file's sha256 (`trust`, ``bounce-gym trust FILE``).

**The manifest** (``manifest.json`` of a folder) records the sha256 of every file this package
saved there: `read_model` refuses a listed file whose content changed since (damaged, or
replaced), unless the user trusts the new content; a file it does not list loads like any other.
The manifest maps a file name to the list of its accepted digests: one, except for the instant
of a save, when the new digest is added before the file is renamed into place and the old one
dropped after, so that a crash at any instant leaves a correctly listed file. Several processes
may save into one folder at once (the seeds of a training sweep, the trials of a search,
`bounce_gym_experiments.training`): each reads, changes and rewrites the manifest under an exclusive lock
(`bounce_gym.files.locked`), so no update is lost.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import pickle
import re
import struct
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

from bounce_gym.documents import Limits, parse_document
from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_file, atomic_write, check_path_component, locked
from bounce_gym.trust import add_trusted, digest, sign, trusted_digests, verify

#: The learners of Stable-Baselines3 and sb3-contrib (`baselines.rl.train`).
SB3_ALGOS = ("ppo", "dqn", "recurrentppo")
#: The learners trained in JAX (`baselines.rl.jaxrl`): their files hold weights only.
JAX_ALGOS = ("jax_ppo", "jax_dqn")
#: The multi-robot learners in torch (`baselines.rl.marl`): their files hold weights only too.
MARL_ALGOS = ("ippo", "mappo")
#: The learners whose files are weights only (an ``.npz``) and metadata, no SB3 part.
WEIGHTS_ALGOS = (*JAX_ALGOS, *MARL_ALGOS)
#: Every learner, by the library that implements it (``bounce-gym train --help`` lists them so).
ALGO_FAMILIES = {"SB3": SB3_ALGOS, "JAX": JAX_ALGOS, "multi-robot": MARL_ALGOS}
ALGOS = tuple(algo for family in ALGO_FAMILIES.values() for algo in family)
_RUN = r"(?P<algo>" + "|".join(ALGOS) + r")(?:-(?P<variant>[a-z0-9]+(?:-[a-z0-9]+)*))?"
#: A saved model: ``<algo>[-<variant>]_seed<seed>.zip``.
MODEL_NAME = re.compile(_RUN + r"_seed(?P<seed>\d+)\.zip")
#: A checkpoint: ``<algo>[-<variant>]_seed<seed>_<steps>_steps.zip``.
CHECKPOINT_NAME = re.compile(_RUN + r"_seed(?P<seed>\d+)_(?P<steps>\d+)_steps\.zip")
#: A variant name: lower-case letters and digits, in parts joined by ``-``.
VARIANT = re.compile(r"[a-z0-9]+(?:-[a-z0-9]+)*")
MANIFEST = "manifest.json"
#: The zip entry of Stable-Baselines3's attributes of the algorithm (JSON).
DATA_ENTRY = "data"
#: The zip entry of a JAX learner's weights (an ``.npz``, read without pickle).
WEIGHTS_ENTRY = "weights.npz"
#: The zip entry holding this package's metadata of a model (JSON).
METADATA_ENTRY = "bounce_gym.json"
#: The zip entry where Stable-Baselines3 writes the OS, Python and library versions (text).
SB3_SYSTEM_INFO = "system_info.txt"
_MAX_SYSTEM_INFO_BYTES = 4096
#: The zip entry of a checkpoint holding the state resuming needs (a pickle).
RESUME_ENTRY = "bounce_gym_resume.pkl"
#: The zip entry holding the signature of `RESUME_ENTRY` (`bounce_gym.trust.sign`, hex).
SIGNATURE_ENTRY = "bounce_gym_resume.sig"
#: What the signatures of resume states are for (`bounce_gym.trust.sign`).
SIGNATURE_PURPOSE = "resume"
#: The most bytes of a model or checkpoint file, which is read whole.
MAX_FILE_BYTES = 1 << 30
#: The most bytes of a JSON entry (uncompressed) or a manifest.
MAX_JSON_BYTES = 16 << 20
#: how a manifest and a model's JSON entries are read (`bounce_gym.documents`)
_JSON_LIMITS = Limits(bytes=MAX_JSON_BYTES)
#: The most bytes of a resume state (uncompressed); it is hashed before anything else.
MAX_RESUME_BYTES = 4 << 30
_MAX_SIGNATURE_BYTES = 256
#: The module of the policy class each algorithm saves (read from the zip's JSON part).
POLICY_MODULES = {"ppo": "stable_baselines3.common.policies",
                  "dqn": "stable_baselines3.dqn.policies",
                  "recurrentppo": "sb3_contrib.common.recurrent.policies"}
#: What `zipfile` raises for a damaged, truncated or unsupported archive.
ZIP_ERRORS = (zipfile.BadZipFile, zlib.error, EOFError, OSError, NotImplementedError,
              RuntimeError)
#: The compression methods of a model file's entries (and of a JAX learner's ``.npz``
#: members): stored or deflated, which `zipfile` inflates no further than a read asks (and
#: never past an entry's declared size). Its bzip2 and LZMA readers inflate a whole chunk of
#: input at once, however large, before cutting it to that size, so an entry of either could
#: cost any memory: it is refused.
COMPRESSIONS = {zipfile.ZIP_STORED: "stored", zipfile.ZIP_DEFLATED: "deflated"}
#: The bytes `read_entry` inflates at a time.
ENTRY_PIECE = 1 << 20


def run_name(algo: str, variant: str | None = None) -> str:
    """``<algo>`` or ``<algo>-<variant>``: the part of a model's file name before ``_seed``."""
    return algo if not variant else f"{algo}-{variant}"


def check_folder_name(field: str, name: str) -> None:
    """A folder of ``models/`` is named by one plain path component
    (`bounce_gym.files.check_path_component`)."""
    check_path_component(field, name, "the name of a folder in models/")


def model_files(folder: Path) -> list[Path]:
    """The saved models of ``folder`` (files named like `MODEL_NAME`), sorted; none if the
    folder does not exist."""
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if MODEL_NAME.fullmatch(p.name) and p.is_file())


def _read(path: Path, limit: int, what: str) -> bytes:
    """The bytes of the file ``path``, if it holds at most ``limit``."""
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            data = fh.read(size + 1) if size <= limit else b""  # read(n) allocates n bytes
    except OSError as exc:
        raise ConfigError(f"{what} {path}: cannot be read ({exc.strerror or exc})") from None
    if size > limit or len(data) > limit:
        raise ConfigError(f"{what} {path}: holds more than the {limit} bytes such a file may")
    return data


def _manifest(folder: Path) -> dict[str, list[str]]:
    path = folder / MANIFEST
    if not path.is_file():
        return {}
    entries = parse_document(f"model manifest {path}", _read(path, MAX_JSON_BYTES,
                                                            "model manifest"),
                             fmt="json", limits=_JSON_LIMITS)
    if not isinstance(entries, dict) or not all(
            isinstance(v, list) and all(isinstance(d, str) for d in v) for v in entries.values()):
        raise ConfigError(f"model manifest {path}: expected a mapping of file names to lists of "
                          "sha256 digests")
    return entries


def _list(path: Path, digests: list[str]) -> None:
    """Set the digests of ``path`` in its folder's manifest (read and rewritten under the lock,
    so concurrent writers of other files in the folder lose nothing)."""
    with locked(path.parent / MANIFEST):
        entries = _manifest(path.parent)
        entries[path.name] = digests
        atomic_write(path.parent / MANIFEST, (json.dumps(entries, indent=2, sort_keys=True)
                                              + "\n").encode())


def save_model(model, path: Path, metadata: dict | None = None, resume: object = None,
               overwrite: bool = True) -> None:
    """Save an SB3 model to ``path`` atomically, with ``metadata`` (JSON) as its
    `METADATA_ENTRY` and ``resume`` (pickled, and signed with the user's key) as its
    `RESUME_ENTRY`, and record its digest in its folder's manifest (the new digest is listed
    before the rename, the old one dropped after). ``overwrite=False`` refuses a ``path`` that
    exists (checkpoints)."""
    if not overwrite and path.exists():
        raise ConfigError(f"{path}: exists already, and a checkpoint is never overwritten")
    old = _manifest(path.parent).get(path.name, [])
    with atomic_file(path) as fh:
        model.save(fh)
        fh.seek(0)
        with zipfile.ZipFile(fh, "a", compression=zipfile.ZIP_DEFLATED) as archive:
            if metadata is not None:
                archive.writestr(METADATA_ENTRY, json.dumps(metadata, indent=1, sort_keys=True))
            if resume is not None:
                state = pickle.dumps(resume, protocol=pickle.HIGHEST_PROTOCOL)
                archive.writestr(RESUME_ENTRY, state)
                archive.writestr(SIGNATURE_ENTRY, _signature(digest(state)))
        fh.seek(0)
        saved = digest(fh.read())
        _list(path, sorted({*old, saved}))
    _list(path, [saved])


def _signature(state_digest: str) -> str:
    """The signature of a resume state of this sha256: its digest is signed, so that checking
    one reads the state in a stream, however large the entry claims to be."""
    return sign(state_digest.encode(), SIGNATURE_PURPOSE)


def _check_name(path: Path, what: str) -> re.Match:
    match = MODEL_NAME.fullmatch(path.name) or CHECKPOINT_NAME.fullmatch(path.name)
    if match is None:
        raise ConfigError(f"{what} {path}: expected a name <{'|'.join(ALGOS)}>[-<variant>]"
                          "_seed<N>[_<steps>_steps].zip")
    return match


def trust(path: Path) -> str:
    """Record the sha256 of the model or checkpoint file ``path`` among the user's trusted
    digests (`bounce_gym.trust.add_trusted`, outside any models folder); returns it.

    Only resuming needs it: a checkpoint whose resume state this user's runs did not sign (one
    from a colleague, or from a machine with another key) is resumed only once trusted, since
    its resume state is a pickle, and unpickling it runs whatever it says. A trusted file whose
    folder's manifest lists other digests also loads (it was replaced on purpose)."""
    if not path.is_file():
        what = "is not a file" if path.exists() else "does not exist"
        raise ConfigError(f"trust: file {str(path)!r} {what}")
    _check_name(path, "trust:")
    sha256 = digest(_read(path, MAX_FILE_BYTES, "trust:"))
    add_trusted(sha256)
    return sha256


def checked_bytes(path: Path) -> bytes:
    """The content of ``path``, read once (at most `MAX_FILE_BYTES`); a `ConfigError` if its
    folder's manifest lists it with other digests (it changed since it was saved) and the user
    does not trust this content."""
    data = _read(path, MAX_FILE_BYTES, "model")
    listed = _manifest(path.parent).get(path.name)
    sha256 = digest(data)
    if listed is None or sha256 in listed or sha256 in trusted_digests():
        return data
    raise ConfigError(f"model {path}: has changed since it was saved (its sha256 is not the one "
                      f"{path.parent / MANIFEST} lists): the file is damaged or was replaced; if "
                      f"this content is what you want, run: bounce-gym trust {path}")


@dataclass(frozen=True)
class ModelFile:
    """A model file, read once: its algorithm, bytes, the uncompressed size of each zip entry,
    SB3's `DATA_ENTRY` and this package's `METADATA_ENTRY` (``{}`` for a zip saved without it),
    both parsed as JSON."""

    path: Path
    algo: str
    data: bytes
    sizes: dict[str, int]
    sb3_data: dict
    metadata: dict

    def load(self, observation_space, action_space, **load_kwargs):
        """The SB3 model, for an env with these spaces; nothing in the file is unpickled
        (`baselines.rl.model_load.load_model_file`)."""
        from baselines.rl.model_load import load_model_file  # it builds on train_config

        return load_model_file(self, observation_space, action_space, **load_kwargs)

    def trained_with(self) -> dict | None:
        """What the file records of the machine and libraries that trained it: the metadata's
        ``trained_with`` (`bounce_gym.provenance.provenance`, written since it was added), else,
        for an older SB3 file, the lines of SB3's own `SB3_SYSTEM_INFO` (OS, Python and library
        versions, no processor) as ``{"sb3_system_info": {name: value}}``; ``None`` when the
        file records neither (the JAX learners' files saved before it)."""
        record = self.metadata.get("trained_with")
        if isinstance(record, dict):
            return record
        if self.sizes.get(SB3_SYSTEM_INFO, _MAX_SYSTEM_INFO_BYTES + 1) > _MAX_SYSTEM_INFO_BYTES:
            return None
        try:
            with zipfile.ZipFile(io.BytesIO(self.data)) as archive:
                text = read_entry(archive, SB3_SYSTEM_INFO).decode("utf-8", errors="replace")
        except ZIP_ERRORS as exc:
            raise ConfigError(f"model {self.path}: its entry {SB3_SYSTEM_INFO!r} cannot be read "
                              f"({type(exc).__name__}: {exc})") from None
        info = {}
        for line in text.splitlines():
            name, sep, value = line.removeprefix("- ").partition(":")
            if sep and name.strip():
                info[name.strip()] = value.strip()
        return {"sb3_system_info": info} if info else None

    def resume_state(self) -> object:
        """The checkpoint's `RESUME_ENTRY`, unpickled once vouched for: signed by this user's
        runs, or the whole file trusted by its digest (`trust`); otherwise a `ConfigError`."""
        try:
            with zipfile.ZipFile(io.BytesIO(self.data)) as archive:
                if RESUME_ENTRY not in self.sizes:
                    raise ConfigError(f"checkpoint {self.path}: holds no resume state "
                                      f"({RESUME_ENTRY})")
                if self.sizes[RESUME_ENTRY] > MAX_RESUME_BYTES:
                    raise ConfigError(f"checkpoint {self.path}: its resume state holds more "
                                      f"than the {MAX_RESUME_BYTES} bytes it may")
                if not (self._signed(archive) or digest(self.data) in trusted_digests()):
                    raise ConfigError(
                        f"checkpoint {self.path}: its resume state was not written by this "
                        "user's runs (no valid signature under the key of the bounce_gym folder, "
                        "$BOUNCE_GYM_HOME), and unpickling it could run anything; if you trust "
                        f"the file, run: bounce-gym trust {self.path}")
                state = read_entry(archive, RESUME_ENTRY)
        except ZIP_ERRORS as exc:
            raise ConfigError(f"checkpoint {self.path}: its resume state cannot be read "
                              f"({type(exc).__name__}: {exc})") from None
        try:
            return pickle.loads(state)  # noqa: S301  (signed by this user's runs, or trusted)
        except (pickle.UnpicklingError, EOFError, AttributeError, ImportError) as exc:
            raise ConfigError(f"checkpoint {self.path}: its resume state cannot be read "
                              f"({type(exc).__name__}: {exc})") from None

    def _signed(self, archive: zipfile.ZipFile) -> bool:
        """Whether `SIGNATURE_ENTRY` is this user's signature of the resume state (hashed in a
        stream: nothing else of it is read before it is vouched for)."""
        if self.sizes.get(SIGNATURE_ENTRY, _MAX_SIGNATURE_BYTES + 1) > _MAX_SIGNATURE_BYTES:
            return False
        signature = read_entry(archive, SIGNATURE_ENTRY).decode("ascii", errors="replace")
        state_digest = hashlib.sha256()
        with archive.open(RESUME_ENTRY) as state:
            for chunk in iter(lambda: state.read(1 << 20), b""):
                state_digest.update(chunk)
        return verify(state_digest.hexdigest().encode(), signature, SIGNATURE_PURPOSE)


def check_compression(info: zipfile.ZipInfo, what: str) -> None:
    """A `ConfigError` (starting with ``what``) unless the zip entry ``info`` is stored or
    deflated (`COMPRESSIONS`)."""
    if info.compress_type not in COMPRESSIONS:
        raise ConfigError(f"{what} {info.filename!r} is compressed with zip method "
                          f"{info.compress_type}, not stored or deflated as this package and "
                          "numpy write them")


def read_entry(archive: zipfile.ZipFile, entry: str | zipfile.ZipInfo) -> bytes:
    """The content of a zip entry, inflated `ENTRY_PIECE` bytes at a time, and so never past
    its declared size: `zipfile`'s own ``read`` of a whole deflated entry inflates all of its
    compressed input in one call, however far past the declared size that goes, and only then
    cuts it there (an entry declaring 2 bytes whose stream inflates to 1 GiB costs 2 GiB)."""
    with archive.open(entry) as stream:
        return b"".join(iter(lambda: stream.read(ENTRY_PIECE), b""))


def check_declared_size(data: bytes, info: zipfile.ZipInfo, what: str) -> None:
    """A `ConfigError` (starting with ``what``) unless the entry ``info`` of the zip ``data``
    holds exactly the bytes it declares: stored, that many bytes; deflated, a stream that ends
    there. For an entry read whole by code other than this package's (SB3 reads ``data`` with
    `zipfile`'s ``read``, which inflates all of a deflated entry's input at once, past its
    declared size, and the entry's CRC may well be that of its declared part): it costs at
    most the declared size, already checked, to inflate it here."""
    local = data[info.header_offset:info.header_offset + 30]  # then its name and extra field
    if len(local) < 30 or local[:4] != b"PK\x03\x04":
        raise ConfigError(f"{what} {info.filename!r} has no local header where the zip's "
                          "directory says")
    start = info.header_offset + 30 + sum(struct.unpack("<HH", local[26:30]))
    raw = memoryview(data)[start:start + info.compress_size]
    if info.compress_type == zipfile.ZIP_STORED:
        honest = info.compress_size == info.file_size
    else:
        stream = zlib.decompressobj(-zlib.MAX_WBITS)
        honest = (len(stream.decompress(raw, info.file_size + 1)) == info.file_size
                  and stream.eof)
    if not honest:
        raise ConfigError(f"{what} {info.filename!r} holds more or fewer than the "
                          f"{info.file_size} bytes it declares")


def _json_entry(archive: zipfile.ZipFile, data: bytes, sizes: dict[str, int], name: str,
                path: Path) -> dict:
    """The JSON entry ``name`` of the model file ``data`` (opened as ``archive``), a mapping."""
    if sizes[name] > MAX_JSON_BYTES:
        raise ConfigError(f"model {path}: its entry {name!r} holds {sizes[name]} bytes, more than "
                          f"the {MAX_JSON_BYTES} a model file's JSON may")
    check_declared_size(data, archive.getinfo(name), f"model {path}: its entry")
    value = parse_document(f"model {path}: its entry {name!r}", read_entry(archive, name),
                           fmt="json", limits=_JSON_LIMITS)
    if not isinstance(value, dict):
        raise ConfigError(f"model {path}: its entry {name!r} is not a JSON object")
    return value


def read_model(path: Path) -> ModelFile:
    """The model file at ``path`` (named like `MODEL_NAME` or `CHECKPOINT_NAME`), its JSON
    parts parsed; a `ConfigError` naming the file says what is wrong with it. Nothing in it is
    unpickled here."""
    algo = _check_name(path, "model").group("algo")
    data = checked_bytes(path)  # loaded from these bytes: the file may not change in between
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            for info in archive.infolist():
                check_compression(info, f"model {path}: its entry")
            sizes = {info.filename: info.file_size for info in archive.infolist()}
            if algo in WEIGHTS_ALGOS:
                return _weights_model(path, algo, data, archive, sizes)
            if DATA_ENTRY not in sizes:
                raise ConfigError(f"model {path}: not a readable Stable-Baselines3 model file "
                                  f"(it has no {DATA_ENTRY!r} entry)")
            sb3_data = _json_entry(archive, data, sizes, DATA_ENTRY, path)
            metadata = (_json_entry(archive, data, sizes, METADATA_ENTRY, path)
                        if METADATA_ENTRY in sizes else {})
    except ZIP_ERRORS as exc:
        raise ConfigError(f"model {path}: not a readable Stable-Baselines3 model file "
                          f"({type(exc).__name__}: {exc})") from None
    policy = sb3_data.get("policy_class")
    module = policy.get("__module__") if isinstance(policy, dict) else None
    if module != POLICY_MODULES[algo]:
        saved = [a for a, m in POLICY_MODULES.items() if m == module] or [repr(module)]
        raise ConfigError(f"model {path}: its name says {algo}, but it holds a {saved[0]} "
                          f"policy; name it after the algorithm that trained it")
    return ModelFile(path, algo, data, sizes, sb3_data, metadata)


def _weights_model(path: Path, algo: str, data: bytes, archive: zipfile.ZipFile,
                   sizes: dict[str, int]) -> ModelFile:
    """A JAX or multi-robot learner's file (`WEIGHTS_ALGOS`): its weights (`WEIGHTS_ENTRY`,
    read by `baselines.rl.jaxrl.weights`) and its metadata, no SB3 part."""
    for entry in (WEIGHTS_ENTRY, METADATA_ENTRY):
        if entry not in sizes:
            raise ConfigError(f"model {path}: not a readable {algo} model file (it has no "
                              f"{entry!r} entry)")
    return ModelFile(path, algo, data, sizes, {}, _json_entry(archive, data, sizes,
                                                             METADATA_ENTRY, path))


def load_model(path: Path, observation_space, action_space, **load_kwargs):
    """The SB3 model at ``path`` for an env with these spaces (`read_model`,
    `ModelFile.load`)."""
    return read_model(path).load(observation_space, action_space, **load_kwargs)
