"""The sampled drifter models on disk: one ``.npz`` file per model, keyed by a fingerprint of
everything that defines it, under ``<home>/cache/drifter_gcm/`` (``home`` is
`bounce_gym.trust.home`, the user's bounce_gym folder, ``$BOUNCE_GYM_HOME`` if set).

The fingerprint is the sha256 of the flow field's arrays (velocities, axes, times, land) and of
the settings that change the matrices: the refinement, the backend, the start time, the step's duration,
substeps, diffusivity and land rule, the exact model's ρ and cell map (its states and vertical
moves), the samples per cell, the seed, the horizon and the file format. A file holds the
stacked drift matrices (CSR arrays) and a JSON header (a uint8 array, read with
`bounce_gym.documents.parse_document`); it is read with ``allow_pickle=False`` and written
atomically (`bounce_gym.files.atomic_file`). A file that cannot be read, whose header does not
match the fingerprint, or whose matrices are not a valid model is rebuilt and replaced.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from gymnasium import logger

from bounce_gym.cells.drifter import DrifterCells
from bounce_gym.cells.sampled_drifter import SampledDrifterCells
from bounce_gym.documents import parse_document
from bounce_gym.envs.drifters.options import DrifterOptions
from bounce_gym.envs.drifters.sampled import build_sampled_model, grid_model
from bounce_gym.errors import BounceGymError
from bounce_gym.files import atomic_file
from bounce_gym.trust import home

__all__ = ["FORMAT", "cache_path", "fingerprint", "sampled_model"]

#: The file format; a change makes every older file stale.
FORMAT = 1
_FOLDER = ("cache", "drifter_gcm")


def fingerprint(options: DrifterOptions, samples: int, seed: int, horizon: int,
                refine: int) -> str:
    """The hex sha256 of everything that defines the sampled model (module docstring)."""
    field = options.field
    settings = {"format": FORMAT, "backend": options.backend, "start_time": options.start_time,
                "step_seconds": options.step_seconds, "substeps": options.substeps,
                "diffusivity": options.diffusivity, "land_rule": options.land_rule,
                "rho": options.rho, "cell_map": options.cell_map, "samples": samples,
                "seed": seed, "horizon": horizon, "refine": refine, "crs": field.crs}
    h = hashlib.sha256(json.dumps(settings, sort_keys=True).encode())
    for array in (field.u, field.v, field.x, field.y, field.depth, field.land, field.time):
        h.update(b"none" if array is None else
                 f"{array.dtype.str}{array.shape}".encode() + np.ascontiguousarray(array).data)
    return h.hexdigest()


def cache_path(key: str) -> Path:
    """Where the model of fingerprint ``key`` is kept."""
    return home().joinpath(*_FOLDER, f"{key}.npz")


def sampled_model(model: DrifterCells, options: DrifterOptions, samples: int, seed: int,
                  horizon: int, refine: int = 1) -> SampledDrifterCells:
    """The sampled model from the cache, built and stored if missing, stale or corrupt."""
    key = fingerprint(options, samples, seed, horizon, refine)
    path = cache_path(key)
    if path.exists():
        try:
            return _read(path, key, grid_model(model, refine))
        except (BounceGymError, OSError, ValueError, KeyError, EOFError,
                zipfile.BadZipFile) as exc:
            logger.warn(f"the sampled drifter model {path} is unusable ({exc}); rebuilding it")
    built = build_sampled_model(model, options, samples, seed, horizon, refine)
    _write(path, key, built)
    return built


def _write(path: Path, key: str, model: SampledDrifterCells) -> None:
    header = {"format": FORMAT, "fingerprint": key, "n_states": model.n_states,
              "n_steps": model.n_steps, "samples": model.samples, "seed": model.seed,
              "vertical_then_drift": model.vertical_then_drift,
              "doubling_tv": model.doubling_tv, "max_doubling_tv": model.max_doubling_tv}
    stacked = sp.vstack(model.drifts, format="csr")
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(path) as fh:
        np.savez(fh, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8),
                 data=stacked.data, indices=stacked.indices, indptr=stacked.indptr)


def _read(path: Path, key: str, model: DrifterCells) -> SampledDrifterCells:
    with np.load(path, allow_pickle=False) as npz:
        header = parse_document(str(path), npz["header"].tobytes(), fmt="json")
        data, indices, indptr = npz["data"], npz["indices"], npz["indptr"]
    if not isinstance(header, dict) or header.get("format") != FORMAT \
            or header.get("fingerprint") != key:
        raise ValueError("its header does not match the model asked for")
    n, k = header.get("n_states"), header.get("n_steps")
    if n != model.n_states or not isinstance(k, int) or k < 1:
        raise ValueError("its header gives the wrong number of states or steps")
    stacked = sp.csr_matrix((data, indices, indptr), shape=(k * n, n))
    stacked.check_format(full_check=True)
    drifts = [stacked[s * n:(s + 1) * n] for s in range(k)]
    numbers = {name: header.get(name) for name in ("doubling_tv", "max_doubling_tv")}
    if not all(isinstance(v, float) for v in numbers.values()) \
            or not isinstance(header.get("vertical_then_drift"), bool):
        raise ValueError("its header lacks the convergence figures")
    return SampledDrifterCells(model, drifts, vertical_then_drift=header["vertical_then_drift"],
                               samples=header["samples"], seed=header["seed"], **numbers)
