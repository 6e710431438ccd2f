"""The seed convention that keeps training and evaluation apart.

Training runs seed their envs with integers below `EVALUATION_SEEDS_START` (env i of a run with
``seed: s`` gets s + i, so ``s + n_envs`` must not pass it); evaluation episodes use seeds from
`EVALUATION_SEEDS_START` on. An agent is therefore never scored on an episode it was trained on.
"""

from __future__ import annotations

#: The first evaluation seed; every training seed lies below it.
EVALUATION_SEEDS_START = 10_000
