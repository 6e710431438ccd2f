"""The sampled drifter models on disk: one ``.npz`` file per model, keyed by a fingerprint of
everything that defines it, under ``<cache>/drifter_gcm/`` (``<cache>`` is ``$BOUNCE_GYM_CACHE``
if set, else ``<home>/cache`` with ``home`` the user's bounce_gym folder), kept and built once
by `bounce_gym.model_cache`.

The fingerprint is the sha256 of the flow field's arrays (velocities, axes, times, land) and of
the settings that change the matrices: the refinement, the backend, the start time, the step's duration,
substeps, diffusivity and land rule, the exact model's ρ and cell map (its states and vertical
moves), the samples per cell, the seed, the horizon and the file format. A file holds the
stacked drift matrices (CSR arrays) and a JSON header. A file that cannot be read, whose header
does not match the fingerprint, or whose matrices are not a valid model is rebuilt and
replaced, with a warning.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from bounce_gym import model_cache
from bounce_gym.cells.drifter import DrifterCells
from bounce_gym.cells.sampled_drifter import SampledDrifterCells
from bounce_gym.envs.drifters.options import DrifterOptions
from bounce_gym.envs.drifters.sampled import build_sampled_model, grid_model

__all__ = ["FORMAT", "cache_path", "drifter_model_fingerprint", "sampled_drifter_model"]

#: The file format; a change makes every older file stale.
FORMAT = 1


def drifter_model_fingerprint(options: DrifterOptions, samples: int, seed: int, horizon: int,
                refine: int) -> str:
    """The hex sha256 of everything that defines the sampled model (module docstring)."""
    field = options.flow
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
    return model_cache.cache_folder("drifter_gcm") / f"{key}.npz"


def sampled_drifter_model(model: DrifterCells, options: DrifterOptions, samples: int, seed: int,
                  horizon: int, refine: int = 1) -> SampledDrifterCells:
    """The sampled model from the cache, built and stored if missing, stale or corrupt."""
    key = drifter_model_fingerprint(options, samples, seed, horizon, refine)
    path = cache_path(key)

    def load() -> SampledDrifterCells | None:
        stored = model_cache.load_cached(path, FORMAT, key)
        if stored is not None:
            try:
                return _read(*stored, grid_model(model, refine))
            except (ValueError, KeyError, TypeError) as exc:
                model_cache.warn_unusable(path, exc)
        return None

    def build() -> SampledDrifterCells:
        built = build_sampled_model(model, options, samples, seed, horizon, refine)
        _write(path, key, built)
        return built

    return model_cache.cached(path, load, build)


def _write(path: Path, key: str, model: SampledDrifterCells) -> None:
    header = {"format": FORMAT, "fingerprint": key, "n_states": model.n_states,
              "n_steps": model.n_steps, "samples": model.samples, "seed": model.seed,
              "vertical_then_drift": model.vertical_then_drift,
              "doubling_tv": model.doubling_tv, "max_doubling_tv": model.max_doubling_tv}
    stacked = sp.vstack(model.drifts, format="csr")
    model_cache.store(path, header, {"data": stacked.data, "indices": stacked.indices,
                                     "indptr": stacked.indptr})


def _read(header: dict, arrays: dict, model: DrifterCells) -> SampledDrifterCells:
    n, k = header.get("n_states"), header.get("n_steps")
    if n != model.n_states or not isinstance(k, int) or k < 1:
        raise ValueError("its header gives the wrong number of states or steps")
    stacked = sp.csr_matrix((arrays["data"], arrays["indices"], arrays["indptr"]),
                            shape=(k * n, n))
    stacked.check_format(full_check=True)
    drifts = [stacked[s * n:(s + 1) * n] for s in range(k)]
    numbers = {name: header.get(name) for name in ("doubling_tv", "max_doubling_tv")}
    if not all(isinstance(v, float) for v in numbers.values()) \
            or not isinstance(header.get("vertical_then_drift"), bool):
        raise ValueError("its header lacks the convergence figures")
    return SampledDrifterCells(model, drifts, vertical_then_drift=header["vertical_then_drift"],
                               samples=header["samples"], seed=header["seed"], **numbers)
