"""Pin JAX's CPU backend (XLA) to one thread, the budget every learner and env of the
benchmarks gets (torch runs on one thread, the NumPy envs on one core).

Import this module before ``jax`` is first imported: XLA reads its flags once.
"""

from __future__ import annotations

import os
import sys

#: the XLA flags of one CPU thread
ONE_THREAD = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"

#: whether the flags took effect (False: jax was imported before this module)
PINNED = "jax" not in sys.modules
if PINNED:
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {ONE_THREAD}".strip()
