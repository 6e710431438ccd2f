"""The model files of the JAX learners: weights only, as data.

A file (named and saved like every model, `baselines.rl.model_files`: atomically, its sha256 in
the folder's manifest) is a zip of two entries: ``weights.npz`` (`WEIGHTS_ENTRY`: one array per
layer, ``<net>.<k>.w`` and ``<net>.<k>.b``) and ``bounce_gym.json`` (the training configuration
and ``{"jax": {"num_timesteps": ...}}``). Reading it unpickles nothing: the ``.npz`` is read with
``allow_pickle=False``, after its size is checked, and every array must have exactly the name,
shape and dtype (float32) the network its configuration describes needs.
"""

from __future__ import annotations

import io
import zipfile

import numpy as np

from baselines.rl.model_files import WEIGHTS_ENTRY, ZIP_ERRORS, ModelFile
from baselines.rl.train_config import validate_train_config
from bounce_gym.errors import ConfigError

#: The most bytes of a weights entry (uncompressed).
MAX_WEIGHTS_BYTES = 1 << 30


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
    shape), float32."""
    if trained.sizes[WEIGHTS_ENTRY] > MAX_WEIGHTS_BYTES:
        raise ConfigError(f"model {trained.path}: its weights hold more than the "
                          f"{MAX_WEIGHTS_BYTES} bytes they may")
    try:
        with zipfile.ZipFile(io.BytesIO(trained.data)) as archive:
            raw = archive.read(WEIGHTS_ENTRY)
        with np.load(io.BytesIO(raw), allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in npz.files}
    except (*ZIP_ERRORS, ValueError, KeyError) as exc:
        raise ConfigError(f"model {trained.path}: its weights cannot be read "
                          f"({type(exc).__name__}: {exc})") from None
    if set(arrays) != set(shapes):
        raise ConfigError(f"model {trained.path}: holds weights {sorted(arrays)}, but its "
                          f"network has {sorted(shapes)} (train with the same env_kwargs)")
    for name, shape in shapes.items():
        if arrays[name].shape != shape or arrays[name].dtype != np.float32:
            raise ConfigError(f"model {trained.path}: its weights {name!r} are "
                              f"{arrays[name].dtype}{list(arrays[name].shape)}, the network "
                              f"needs float32{list(shape)} (train with the same env_kwargs)")
    return arrays
