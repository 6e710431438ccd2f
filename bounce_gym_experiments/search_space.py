"""Hyperparameter search spaces: a YAML file beside the rl-zoo style hyperparameter files
(``configs/hyperparams/search/<algo>.yaml``) giving each hyperparameter a distribution::

    learning_rate: {loguniform: [1.0e-5, 1.0e-3]}   # log-uniform on [low, high], 0 < low < high
    gamma: {uniform: [0.95, 0.999]}                 # uniform on [low, high], low < high
    n_epochs: {randint: [3, 10]}                    # an integer in [low, high], both included,
                                                    # low < high, both within int64
    n_steps: {choice: [64, 128, 256]}               # one of the values, equally likely
    policy_kwargs: {choice: [{net_arch: [64, 64]}, {net_arch: [128, 128]}]}

`load_search_space` checks the file (read by `bounce_gym.documents`; every mistake a
`ConfigError` naming the field, e.g. ``search.learning_rate.loguniform``): bounds are finite
numbers, a ``choice`` has 1 to `MAX_CHOICES` (10,000) values, and every bound and every value
of a ``choice`` lies within its hyperparameter's range (`baselines.rl.train_config`, e.g.
``gamma`` in (0, 1]), so no draw can leave it. Whether each name is a hyperparameter of the
algorithm is checked with the training configuration it goes into (`bounce_gym_experiments.search`).
`sample_trial` draws the hyperparameters of trial ``k`` from its own random stream, seeded with
``(seed, k)``: a search is reproducible, and running more trials leaves the first ones as they
were.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np

from baselines.rl.train_config import check_range
from bounce_gym.documents import read_document
from bounce_gym.errors import ConfigError

DISTRIBUTIONS = ("loguniform", "uniform", "randint", "choice")
#: Most values of one ``choice``.
MAX_CHOICES = 10_000
#: The bounds a ``randint`` may have (numpy draws int64).
INT64 = (-(2**63), 2**63 - 1)


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
    name, field = field.removeprefix("search."), f"{field}.{kind}"
    if kind == "choice":
        if not isinstance(bounds, list) or not 1 <= len(bounds) <= MAX_CHOICES:
            got = f"{len(bounds)} values" if isinstance(bounds, list) else repr(bounds)
            raise ConfigError(f"{field}: expected a list of 1 to {MAX_CHOICES} values, got "
                              f"{got}")
        for k, choice in enumerate(bounds):
            check_range(f"{field}[{k}]", name, choice)
        return kind, bounds
    numbers = isinstance(bounds, list) and len(bounds) == 2 and all(
        isinstance(b, int | float) and not isinstance(b, bool) and math.isfinite(b)
        for b in bounds)
    if kind == "randint":
        if not numbers or not all(isinstance(b, int) and INT64[0] <= b <= INT64[1]
                                  for b in bounds) or bounds[0] >= bounds[1]:
            raise ConfigError(f"{field}: expected [low, high], integers in [{INT64[0]}, "
                              f"{INT64[1]}] with low < high, got {bounds!r}")
    else:
        least = "0 < low < high" if kind == "loguniform" else "low < high"
        if not numbers or bounds[0] >= bounds[1] or kind == "loguniform" and bounds[0] <= 0:
            raise ConfigError(f"{field}: expected [low, high], numbers with {least}, got "
                              f"{bounds!r}")
        bounds = [float(b) for b in bounds]
    for k, bound in enumerate(bounds):
        check_range(f"{field}[{k}]", name, bound)
    return kind, tuple(bounds)


def sample_trial(space: dict[str, tuple[str, object]], seed: int, trial: int) -> dict:
    """The hyperparameters of trial ``trial``: one draw from each distribution, in the file's
    order, from the random stream of ``(seed, trial)``."""
    rng = np.random.default_rng([seed, trial])
    values = {}
    for key, (kind, bounds) in space.items():
        if kind == "choice":
            values[key] = copy.deepcopy(bounds[int(rng.integers(len(bounds)))])
        elif kind == "randint":
            values[key] = int(rng.integers(bounds[0], bounds[1], endpoint=True))
        elif kind == "uniform":
            values[key] = float(rng.uniform(*bounds))
        else:
            values[key] = float(np.exp(rng.uniform(np.log(bounds[0]), np.log(bounds[1]))))
    return values
