"""Model files: their folder and file names, saving them atomically, and trusting them.

`baselines.rl.train` saves a model as ``<models>/<name>/<algo>_seed<seed>.zip`` (`MODEL_NAME`);
the evaluation loads only files with such names, never temporary or partial ones.

**Trust.** A Stable-Baselines3 zip is code as much as data: loading one unpickles parts of it,
and a pickle can run anything. So every model file this package saves is listed, with its
sha256, in ``manifest.json`` of its folder (written atomically, like the model), and
`load_model` refuses a file that is not listed or whose content changed since — before reading
any of it. `trust` (the command ``bounce-gym trust FILE``) lists a file obtained elsewhere.

The manifest maps a file name to the list of its accepted sha256 digests: one, except for the
instant of a save, when the new digest is added before the file is renamed into place and the
old one dropped after, so that a crash at any instant leaves a listed file.
"""

from __future__ import annotations

import hashlib
import io
import json
import re
import zipfile
from pathlib import Path

from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_file, atomic_write

#: The name of a saved model: ``<algo>_seed<seed>.zip``.
MODEL_NAME = re.compile(r"(ppo|dqn|recurrentppo)_seed(\d+)\.zip")
MANIFEST = "manifest.json"
#: The module of the policy class each algorithm saves (read from the zip's JSON part).
POLICY_MODULES = {"ppo": "stable_baselines3.common.policies",
                  "dqn": "stable_baselines3.dqn.policies",
                  "recurrentppo": "sb3_contrib.common.recurrent.policies"}


def check_folder_name(field: str, name: str) -> None:
    """A folder of ``models/`` is named by one plain path component (no ``/``, ``..``)."""
    if not name or name in (".", "..") or Path(name).name != name or "\\" in name \
            or "\0" in name:
        raise ConfigError(f"{field}: expected the name of a folder in models/ (no '/' or '..'), "
                          f"got {name!r}")


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
    entries = _manifest(path.parent)
    entries[path.name] = digests
    atomic_write(path.parent / MANIFEST, (json.dumps(entries, indent=2, sort_keys=True)
                                          + "\n").encode())


def save_model(model, path: Path) -> None:
    """Save an SB3 model to ``path`` atomically and list it in its folder's manifest."""
    old = _manifest(path.parent).get(path.name, [])
    with atomic_file(path) as fh:
        model.save(fh)
        fh.seek(0)
        digest = _digest(fh.read())
        _list(path, sorted({*old, digest}))
    _list(path, [digest])


def trust(path: Path) -> str:
    """List the model file ``path`` in its folder's manifest; returns its sha256."""
    if not path.is_file():
        raise ConfigError(f"trust: file {str(path)!r} does not exist")
    if not MODEL_NAME.fullmatch(path.name):
        raise ConfigError(f"trust: {str(path)!r} is not named like a model, "
                          "<ppo|dqn|recurrentppo>_seed<N>.zip")
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


def load_model(path: Path, observation_space, action_space, **load_kwargs):
    """The trusted SB3 model at ``path`` (``<algo>_seed<N>.zip``) for an env with these spaces;
    a `ConfigError` naming the file says what is wrong with it."""
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import DQN, PPO

    match = MODEL_NAME.fullmatch(path.name)
    if match is None:
        raise ConfigError(f"model {path}: expected a name <ppo|dqn|recurrentppo>_seed<N>.zip")
    algo = match.group(1)
    data = trusted_bytes(path)  # loaded from these bytes: the file may not change in between
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            module = json.loads(archive.read("data"))["policy_class"]["__module__"]
    except (zipfile.BadZipFile, KeyError, TypeError, ValueError, OSError) as exc:
        raise ConfigError(f"model {path}: not a readable Stable-Baselines3 model file "
                          f"({type(exc).__name__}: {exc})") from None
    if module != POLICY_MODULES[algo]:
        saved = [a for a, m in POLICY_MODULES.items() if m == module] or [module]
        raise ConfigError(f"model {path}: its name says {algo}, but it holds a {saved[0]} "
                          f"policy; name it after the algorithm that trained it")
    algo_class = {"ppo": PPO, "dqn": DQN, "recurrentppo": RecurrentPPO}[algo]
    try:
        model = algo_class.load(io.BytesIO(data), device="cpu", **load_kwargs)
    except (zipfile.BadZipFile, AssertionError, KeyError, RuntimeError, ValueError,
            EOFError) as exc:
        raise ConfigError(f"model {path}: cannot be loaded as {algo} "
                          f"({type(exc).__name__}: {exc})") from None
    if model.observation_space != observation_space or model.action_space != action_space:
        raise ConfigError(
            f"model {path}: trained for observations {model.observation_space} and actions "
            f"{model.action_space}, but this env has {observation_space} and {action_space} "
            "(train with the same env_kwargs)")
    return model
