"""The seed convention: three disjoint ranges, one per use.

* **Training** (`TRAINING_SEEDS`, [0, 9000)): a training run with ``seed: s`` and ``n_envs``
  envs seeds env i with s + i, so s + n_envs must not pass `TRAINING_SEEDS.stop`.
* **Tuning** (`TUNING_SEEDS`, [9000, 10000)): every episode that chooses a setting of a planner,
  filter or learner (a Ray Tune trial's score, a comparison of filter settings).
* **Evaluation** (`EVALUATION_SEEDS`, from `EVALUATION_SEEDS_START` = 10000 to `MAX_SEED`):
  the episodes that results are reported on.

An agent is therefore never scored on an episode it was trained on, and no reported figure comes
from an episode a setting was chosen on.
"""

from __future__ import annotations

#: the largest seed a configuration may name (NumPy's legacy seeding takes 32-bit integers)
MAX_SEED = 2**32 - 1
#: seeds of training envs (a run's env i gets seed + i)
TRAINING_SEEDS = range(0, 9_000)
#: seeds of the episodes that tune a planner's, filter's or learner's settings
TUNING_SEEDS = range(TRAINING_SEEDS.stop, 10_000)
#: the first evaluation seed
EVALUATION_SEEDS_START = TUNING_SEEDS.stop
#: seeds of the episodes that results are reported on
EVALUATION_SEEDS = range(EVALUATION_SEEDS_START, MAX_SEED + 1)

#: the ranges an evaluation seed must stay out of, by name
RESERVED_SEEDS = {"training": TRAINING_SEEDS, "tuning": TUNING_SEEDS}


def reserved_overlap(seeds: range) -> str | None:
    """Why ``seeds`` may not be evaluation seeds: the first reserved range they meet, as
    ``"the tuning seeds [9000, 10000)"``, or None if they meet none."""
    for name, reserved in RESERVED_SEEDS.items():
        if max(seeds.start, reserved.start) < min(seeds.stop, reserved.stop):
            return f"the {name} seeds [{reserved.start}, {reserved.stop})"
    return None
