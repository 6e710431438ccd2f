"""Hyperparameter search spaces: a YAML file beside the rl-zoo style hyperparameter files
(``configs/hyperparams/search/<algo>.yaml``) giving each hyperparameter a distribution::

    learning_rate: {loguniform: [1.0e-5, 1.0e-3]}   # log-uniform on [low, high], 0 < low < high
    gamma: {uniform: [0.95, 0.999]}                 # uniform on [low, high], low < high
    n_epochs: {randint: [3, 10]}                    # an integer in [low, high], both included
    n_steps: {choice: [64, 128, 256]}               # one of the values, equally likely
    policy_kwargs: {choice: [{net_arch: [64, 64]}, {net_arch: [128, 128]}]}

`load_search_space` checks the file (every mistake a `ConfigError` naming the field, e.g.
``search.learning_rate.loguniform``); whether each name is a hyperparameter of the algorithm is
checked with the training configuration it goes into (`experiments.search`). `sample` draws the
hyperparameters of trial ``k`` from its own random stream, seeded with ``(seed, k)``: a search
is reproducible, and running more trials leaves the first ones as they were.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np

from bounce_gym.documents import read_document
from bounce_gym.errors import ConfigError

DISTRIBUTIONS = ("loguniform", "uniform", "randint", "choice")


def load_search_space(path: Path) -> dict[str, tuple[str, object]]:
    """The search space of the YAML file ``path``: per hyperparameter, its distribution's name
    and its bounds (or, for ``choice``, its values)."""
    entries = read_document(path, "search")
    if not isinstance(entries, dict) or not entries:
        raise ConfigError(f"search: {path} must map hyperparameter names to distributions, "
                          f"e.g. learning_rate: {{loguniform: [1.0e-5, 1.0e-3]}}")
    return {str(key): _distribution(f"search.{key}", value) for key, value in entries.items()}


def _distribution(field: str, value: object) -> tuple[str, object]:
    if not isinstance(value, dict) or len(value) != 1 or next(iter(value)) not in DISTRIBUTIONS:
        raise ConfigError(f"{field}: expected one of {{{', '.join(DISTRIBUTIONS)}: ...}}, got "
                          f"{value!r}")
    (kind, bounds), = value.items()
    field = f"{field}.{kind}"
    if kind == "choice":
        if not isinstance(bounds, list) or not bounds:
            raise ConfigError(f"{field}: expected a non-empty list of values, got {bounds!r}")
        return kind, bounds
    numbers = isinstance(bounds, list) and len(bounds) == 2 and all(
        isinstance(b, int | float) and not isinstance(b, bool) and math.isfinite(b)
        for b in bounds)
    if kind == "randint":
        if not numbers or not all(isinstance(b, int) for b in bounds) or bounds[0] > bounds[1]:
            raise ConfigError(f"{field}: expected [low, high], integers with low <= high, got "
                              f"{bounds!r}")
        return kind, (bounds[0], bounds[1])
    least = "0 < low < high" if kind == "loguniform" else "low < high"
    if not numbers or bounds[0] >= bounds[1] or kind == "loguniform" and bounds[0] <= 0:
        raise ConfigError(f"{field}: expected [low, high], numbers with {least}, got {bounds!r}")
    return kind, (float(bounds[0]), float(bounds[1]))


def sample(space: dict[str, tuple[str, object]], seed: int, trial: int) -> dict:
    """The hyperparameters of trial ``trial``: one draw from each distribution, in the file's
    order, from the random stream of ``(seed, trial)``."""
    rng = np.random.default_rng([seed, trial])
    values = {}
    for key, (kind, bounds) in space.items():
        if kind == "choice":
            values[key] = copy.deepcopy(bounds[int(rng.integers(len(bounds)))])
        elif kind == "randint":
            values[key] = int(rng.integers(bounds[0], bounds[1] + 1))
        elif kind == "uniform":
            values[key] = float(rng.uniform(*bounds))
        else:
            values[key] = float(np.exp(rng.uniform(np.log(bounds[0]), np.log(bounds[1]))))
    return values
