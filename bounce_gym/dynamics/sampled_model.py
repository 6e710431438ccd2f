"""The sampled generalized cell mapping of an env, built once and cached on disk.

`sampled_model` estimates the bump-to-bump GCM of a world under the env's own dynamics
(`bounce_gym.dynamics.bump_sampler`), with ``samples`` sample points per decision state and
angle, from one seeded generator. The estimate states its convergence: the total-variation
distance between the next-state distributions of two independent halves of the samples, mean
and largest over the (state, angle) pairs (`SampledModel.convergence`).

**Cache.** The result depends only on what is fingerprinted (`model_fingerprint`: the world's
geometry, the cell grid, the dynamics — backend, physics and its parameters, rule, noise, radius,
step length —, Φ, the samples, the seed, the heading offset, the re-sampling rounds and
`FORMAT`); it is stored as
``<fingerprint>.npz`` holding the sample arrays and a JSON header, by `bounce_gym.model_cache` (data only, written
atomically). A file that cannot be read, is inconsistent or whose header names another
fingerprint is rebuilt and replaced, with a warning. The folder is ``cache`` when given, else
``<cache>/sampled_models`` (`bounce_gym.model_cache.cache_folder`: ``$BOUNCE_GYM_CACHE``, or
``<home>/cache`` with ``$BOUNCE_GYM_HOME`` or the user's config folder); ``cache=False`` keeps
the model in memory only.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bounce_gym import model_cache
from bounce_gym.cells.model import CellModel
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.dynamics.bump_sampler import (
    EXPLORE,
    ROUNDS,
    default_max_ticks,
    first_bumps,
    sample_outcomes,
    simulate_bumps,
)
from bounce_gym.errors import ConfigError

#: the version of the stored layout and of the construction; a change invalidates old files
FORMAT = 6
#: default sample points per decision state and angle
DEFAULT_SAMPLES = 200


@dataclass(frozen=True)
class SampledModel:
    """A GCM estimated from the simulator (module docstring).

    Attributes:
        model: the cell model whose cell numbers are the decision states.
        outcomes: the sample points and their outcomes (P(z', ticks | z, a) is
            ``outcomes.transitions()``).
        dynamics: the `BounceDynamics` arguments that simulated them (``world`` included).
        samples, seed, offset: sample points per state and angle, the generator's seed, the
            heading offset (radians, None: spread over the bin).
        fingerprint: the cache key.
        max_ticks: the longest simulated drive.
        convergence: ``tv_halves_mean`` and ``tv_halves_max``: total-variation distance between
            the estimates of two independent halves of the samples.
    """

    model: CellModel
    outcomes: BumpOutcomes
    dynamics: dict
    samples: int
    seed: int
    offset: float | None
    fingerprint: str
    convergence: dict
    max_ticks: int

    def first_states(self, position: np.ndarray, heading: float, n: int,
                     rng: np.random.Generator
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Decision states, contact points, headings and clocks of ``n`` simulated robots after
        a bounce-mode reset drive from a known start pose
        (`bounce_gym.dynamics.bump_sampler.first_bumps`)."""
        return first_bumps(self.model, position, heading, n, rng, self.dynamics, self.max_ticks)

    def step(self, action: np.ndarray, point: np.ndarray, heading: np.ndarray,
             rng: np.random.Generator) -> BumpOutcomes:
        """Robots at bump poses bump with the angles ``action`` (indices into Φ) and drive to
        their next bump under the same dynamics (`bounce_gym.dynamics.bump_sampler.simulate_bumps`):
        one outcome per robot."""
        return simulate_bumps(self.model, self.outcomes.angles, action, point, heading, rng,
                              self.dynamics, self.max_ticks)


def model_fingerprint(model: CellModel, dynamics: dict, angles: np.ndarray, samples: int, seed: int,
                offset: float | None, max_ticks: int) -> str:
    """The sha256 (hex) of everything that defines a sampled model."""
    described = {
        "format": FORMAT,
        "world": dynamics["world"].to_dict(),
        "grid": [model.cell_size, model.n_bins, model.robot_radius, model.corner_rule],
        "dynamics": {k: repr(v) for k, v in sorted(dynamics.items()) if k != "world"},
        "angles": [float.hex(float(a)) for a in np.asarray(angles, dtype=np.float64)],
        "samples": samples, "seed": seed, "max_ticks": max_ticks,
        "rounds": ROUNDS, "explore": EXPLORE,
        "offset": None if offset is None else float.hex(float(offset)),
    }
    text = json.dumps(described, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def default_cache() -> Path:
    """``<cache>/sampled_models`` (module docstring)."""
    return model_cache.cache_folder("sampled_models")


def sampled_model(model: CellModel, dynamics: dict, angles: np.ndarray,
                  samples: int = DEFAULT_SAMPLES, seed: int = 0, offset: float | None = None,
                  max_ticks: int | None = None, cache: Path | str | bool | None = None
                  ) -> SampledModel:
    """The sampled GCM of ``model`` under ``dynamics`` (`BounceDynamics` arguments with the
    ``world``) for the bounce ``angles`` (radians), from the cache or built (module docstring).

    ``max_ticks`` (default: four drives across the world's diameter) bounds a simulated drive;
    ``cache``: a folder, None for the default one, False for none."""
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise ConfigError(f"samples: expected an integer >= 2, got {samples!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"seed: expected an integer >= 0, got {seed!r}")
    if max_ticks is None:
        max_ticks = default_max_ticks(dynamics)
    key = model_fingerprint(model, dynamics, angles, samples, seed, offset, max_ticks)

    def finished(outcomes: BumpOutcomes, convergence: dict) -> SampledModel:
        return SampledModel(model, outcomes, dict(dynamics), samples, seed, offset, key,
                            convergence, max_ticks)

    def build(path: Path | None) -> SampledModel:
        outcomes = sample_outcomes(model, angles, samples, np.random.default_rng(seed), dynamics,
                                   max_ticks, offset)
        tv = outcomes.split(0).total_variation(outcomes.split(1))
        convergence = {"tv_halves_mean": float(np.nanmean(tv)),
                       "tv_halves_max": float(np.nanmax(tv))}
        if path is not None:
            _store(path, outcomes, key, convergence)
        return finished(outcomes, convergence)

    if cache is False:
        return build(None)
    path = Path(default_cache() if cache is None or cache is True else cache) / f"{key}.npz"

    def load() -> SampledModel | None:
        stored = _load(path, model, key)
        return None if stored is None else finished(*stored)

    return model_cache.cached(path, load, lambda: build(path))


def _store(path: Path, outcomes: BumpOutcomes, key: str, convergence: dict) -> None:
    header = {"format": FORMAT, "fingerprint": key, "n_cells": outcomes.n_cells,
              "convergence": convergence}
    model_cache.store(path, header, outcomes.arrays())


def _load(path: Path, model: CellModel, key: str) -> tuple[BumpOutcomes, dict] | None:
    """The stored outcomes and convergence at ``path``, or None when it is missing, unreadable,
    inconsistent or stale (`bounce_gym.model_cache`)."""
    stored = model_cache.load_cached(path, FORMAT, key)
    if stored is None:
        return None
    header, arrays = stored
    try:
        convergence = header.get("convergence")
        if header.get("n_cells") != model.n_cells or not isinstance(convergence, dict):
            raise ValueError("its header does not match the cell model")
        return BumpOutcomes.from_arrays(model.n_cells, arrays), convergence
    except (ValueError, KeyError, TypeError) as exc:
        model_cache.warn_unusable(path, exc)
        return None
