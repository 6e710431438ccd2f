"""Model files: their names, saving them atomically, and trusting them.

`baselines.rl.train` saves, in ``<models>/<name>/``:

* the model ``<run>_seed<seed>.zip`` (`MODEL_NAME`), where ``<run>`` is the algorithm, optionally
  followed by ``-<variant>`` (``ppo``, ``ppo-stack4``, ``recurrentppo``, ``dqn``); the evaluation
  loads only files with such names, never temporary or partial ones;
* checkpoints ``checkpoints/<run>_seed<seed>_<steps>_steps.zip`` (`CHECKPOINT_NAME`), never
  overwritten.

A model zip is Stable-Baselines3's file plus entries of its own, which SB3 ignores:
``bounce_gym.json`` (`METADATA_ENTRY`: the training configuration and the observation wrappers
the model was trained behind — frame stacking, VecNormalize statistics, `baselines.rl.wrappers`
— so the evaluation rebuilds them from the same trusted file) and, in a checkpoint,
``bounce_gym_resume.pkl`` (`RESUME_ENTRY`: what resuming needs besides the weights and the
optimiser, `baselines.rl.resume`). One file holds a whole checkpoint, so a crash leaves either
all of it or none.

**Trust.** A Stable-Baselines3 zip is code as much as data: loading one unpickles parts of it,
and a pickle can run anything. So every model file this package saves is listed, with its
sha256, in ``manifest.json`` of its folder (written atomically, like the file), and
`read_model` refuses a file that is not listed or whose content changed since — before reading
any of it. `trust` (the command ``bounce-gym trust FILE``) lists a file obtained elsewhere.

The manifest maps a file name to the list of its accepted sha256 digests: one, except for the
instant of a save, when the new digest is added before the file is renamed into place and the
old one dropped after, so that a crash at any instant leaves a listed file. Several processes may
save into one folder at once (the seeds of a training sweep, the trials of a search,
`experiments.training`): each reads, changes and rewrites the manifest under an exclusive lock
(`bounce_gym.files.locked`), so no update is lost.
"""

from __future__ import annotations

import hashlib
import io
import json
import pickle
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path

from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_file, atomic_write, check_path_component, locked

ALGOS = ("ppo", "dqn", "recurrentppo")
_RUN = r"(?P<algo>ppo|dqn|recurrentppo)(?:-(?P<variant>[a-z0-9]+(?:-[a-z0-9]+)*))?"
#: A saved model: ``<algo>[-<variant>]_seed<seed>.zip``.
MODEL_NAME = re.compile(_RUN + r"_seed(?P<seed>\d+)\.zip")
#: A checkpoint: ``<algo>[-<variant>]_seed<seed>_<steps>_steps.zip``.
CHECKPOINT_NAME = re.compile(_RUN + r"_seed(?P<seed>\d+)_(?P<steps>\d+)_steps\.zip")
#: A variant name: lower-case letters and digits, in parts joined by ``-``.
VARIANT = re.compile(r"[a-z0-9]+(?:-[a-z0-9]+)*")
MANIFEST = "manifest.json"
#: The zip entry holding this package's metadata of a model (JSON).
METADATA_ENTRY = "bounce_gym.json"
#: The zip entry of a checkpoint holding the state resuming needs (a pickle).
RESUME_ENTRY = "bounce_gym_resume.pkl"
#: The module of the policy class each algorithm saves (read from the zip's JSON part).
POLICY_MODULES = {"ppo": "stable_baselines3.common.policies",
                  "dqn": "stable_baselines3.dqn.policies",
                  "recurrentppo": "sb3_contrib.common.recurrent.policies"}


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


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _manifest(folder: Path) -> dict[str, list[str]]:
    path = folder / MANIFEST
    if not path.is_file():
        return {}
    try:
        entries = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, OSError) as exc:
        raise ConfigError(f"model manifest {path}: cannot be read ({exc})") from None
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
    `METADATA_ENTRY` and ``resume`` (pickled) as its `RESUME_ENTRY`, and list it in its folder's
    manifest (the new digest is listed before the rename, the old one dropped after).
    ``overwrite=False`` refuses a ``path`` that exists (checkpoints)."""
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
                archive.writestr(RESUME_ENTRY,
                                 pickle.dumps(resume, protocol=pickle.HIGHEST_PROTOCOL))
        fh.seek(0)
        digest = _digest(fh.read())
        _list(path, sorted({*old, digest}))
    _list(path, [digest])


def trust(path: Path) -> str:
    """List the file ``path`` (a model or a checkpoint) in its folder's manifest;
    returns its sha256."""
    if not path.is_file():
        raise ConfigError(f"trust: file {str(path)!r} does not exist")
    if not (MODEL_NAME.fullmatch(path.name) or CHECKPOINT_NAME.fullmatch(path.name)):
        raise ConfigError(f"trust: {str(path)!r} is not named like a model, "
                          "<ppo|dqn|recurrentppo>[-<variant>]_seed<N>[_<steps>_steps].zip")
    digest = _digest(path.read_bytes())
    _list(path, [digest])
    return digest


def trusted_bytes(path: Path) -> bytes:
    """The content of ``path``, read once; a `ConfigError` unless its sha256 is listed in its
    folder's manifest."""
    data = path.read_bytes()
    digest = _digest(data)
    listed = _manifest(path.parent).get(path.name)
    if listed is not None and digest in listed:
        return data
    why = ("is not listed in" if listed is None else
           "has changed since it was listed in")
    raise ConfigError(f"model {path}: {why} {path.parent / MANIFEST} (a model file runs code "
                      f"when loaded); if you trust it, run: bounce-gym trust {path}")


@dataclass(frozen=True)
class ModelFile:
    """A trusted model file, read once: its algorithm, bytes and `METADATA_ENTRY` (``{}`` for a
    zip saved without it)."""

    path: Path
    algo: str
    data: bytes
    metadata: dict

    def load(self, observation_space, action_space, **load_kwargs):
        """The SB3 model, checked to be trained for an env with these spaces."""
        from sb3_contrib import RecurrentPPO
        from stable_baselines3 import DQN, PPO

        algo_class = {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}[self.algo]
        try:
            model = algo_class.load(io.BytesIO(self.data), device="cpu", **load_kwargs)
        except (zipfile.BadZipFile, AssertionError, KeyError, RuntimeError, ValueError,
                EOFError) as exc:
            raise ConfigError(f"model {self.path}: cannot be loaded as {self.algo} "
                              f"({type(exc).__name__}: {exc})") from None
        if model.observation_space != observation_space or model.action_space != action_space:
            raise ConfigError(
                f"model {self.path}: trained for observations {model.observation_space} and "
                f"actions {model.action_space}, but this env has {observation_space} and "
                f"{action_space} (train with the same env_kwargs)")
        return model

    def resume_state(self) -> object:
        """The checkpoint's `RESUME_ENTRY`, unpickled (the file is trusted); a `ConfigError` if
        it has none."""
        try:
            with zipfile.ZipFile(io.BytesIO(self.data)) as archive:
                data = archive.read(RESUME_ENTRY)
        except KeyError:
            raise ConfigError(f"checkpoint {self.path}: holds no resume state "
                              f"({RESUME_ENTRY})") from None
        try:
            return pickle.loads(data)  # noqa: S301  (trusted: listed with this sha256)
        except (pickle.UnpicklingError, EOFError, AttributeError, ImportError) as exc:
            raise ConfigError(f"checkpoint {self.path}: its resume state cannot be read "
                              f"({type(exc).__name__}: {exc})") from None


def read_model(path: Path) -> ModelFile:
    """The trusted model file at ``path`` (named like `MODEL_NAME` or `CHECKPOINT_NAME`); a
    `ConfigError` naming the file says what is wrong with it. Nothing in it is unpickled here."""
    match = MODEL_NAME.fullmatch(path.name) or CHECKPOINT_NAME.fullmatch(path.name)
    if match is None:
        raise ConfigError(f"model {path}: expected a name <ppo|dqn|recurrentppo>[-<variant>]"
                          "_seed<N>.zip")
    algo = match.group("algo")
    data = trusted_bytes(path)  # loaded from these bytes: the file may not change in between
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            module = json.loads(archive.read("data"))["policy_class"]["__module__"]
            names = archive.namelist()
            metadata = (json.loads(archive.read(METADATA_ENTRY)) if METADATA_ENTRY in names
                        else {})
    except (zipfile.BadZipFile, KeyError, TypeError, ValueError, OSError) as exc:
        raise ConfigError(f"model {path}: not a readable Stable-Baselines3 model file "
                          f"({type(exc).__name__}: {exc})") from None
    if not isinstance(metadata, dict):
        raise ConfigError(f"model {path}: its {METADATA_ENTRY} is not a JSON object")
    if module != POLICY_MODULES[algo]:
        saved = [a for a, m in POLICY_MODULES.items() if m == module] or [module]
        raise ConfigError(f"model {path}: its name says {algo}, but it holds a {saved[0]} "
                          f"policy; name it after the algorithm that trained it")
    return ModelFile(path, algo, data, metadata)


def load_model(path: Path, observation_space, action_space, **load_kwargs):
    """The trusted SB3 model at ``path`` for an env with these spaces (`read_model`)."""
    return read_model(path).load(observation_space, action_space, **load_kwargs)
