"""The test run's folders, never the user's, and its time budget.

A run keeps everything it writes outside the tests' own ``tmp_path`` in one temporary folder,
removed at its end, and tells the processes its tests start through the environment, which they
inherit:

* ``home-<worker>``: the user-level bounce_gym folder (``$BOUNCE_GYM_HOME``: the signing key and
  the trusted digests, `bounce_gym.trust`), one per pytest-xdist worker (``main`` without
  xdist), so no test sees a key or a digest another worker's test wrote;
* ``cache``: the models the suite builds from a simulator (``$BOUNCE_GYM_CACHE``: bump tables,
  sampled cell mappings, drifter models; `bounce_gym.model_cache`), shared by every worker and
  found by fingerprint, so each is built once per run (`bounce_gym.model_cache.cached` holds a
  lock while one is built);
* ``jax``: JAX's persistent compilation cache, so a function compiled by one worker or one
  started process is read back by the others.

The folder is made by the process that runs pytest (the controller under xdist) and handed to
its workers through `RUN_VARIABLE`.

Each worker owns one core: with no more workers than cores, worker ``gw<i>`` and every process
it starts run on the i-th core this run may use (``sched_setaffinity``), so a test's process pool
or Ray instance sized to "the machine's cores" (`bounce_gym_experiments.executors.machine_cores`)
takes its worker's core and does not crowd the others'. Each worker computes on one thread
(OpenMP, OpenBLAS, MKL, XLA's CPU backend; torch reads ``OMP_NUM_THREADS``) unless the caller's
environment says otherwise: the workers already fill the cores, and a multi-threaded BLAS beside
a busy worker spins (a cvxpy solve that takes 0.9 s alone took 36 s so). These are set before
NumPy is first imported.

Tests marked ``long`` (a minute or more on one core) are run first: a worker that starts one
near the end of a run would keep the others waiting for it.

The budget: `make test` (``-m "not slow"``) and `make test-slow` (``-m slow``) run on one worker
per core and must finish within `BUDGET_MINUTES` on the project's 2-core machine; the summary
prints the run's wall time beside its budget (tests never assert a wall-clock time: this keeps the
figure in sight), and ``--durations=20`` lists the slowest tests.
"""

import os

for _threads in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_threads, "1")
os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false "
                                   "intra_op_parallelism_threads=1")

import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

from bounce_gym.model_cache import CACHE_VARIABLE  # noqa: E402
from bounce_gym.trust import HOME_VARIABLE  # noqa: E402

#: the variable through which the controller hands the run's folder to its workers
RUN_VARIABLE = "BOUNCE_GYM_TEST_RUN"
#: minutes each suite may take on the project's 2-core machine, by its ``-m`` expression
BUDGET_MINUTES = {"not slow": 8, "slow": 15}

_WORKER = os.environ.get("PYTEST_XDIST_WORKER")
_OWNER = _WORKER is None or RUN_VARIABLE not in os.environ
if _OWNER:
    os.environ[RUN_VARIABLE] = tempfile.mkdtemp(prefix="bounce-gym-tests-")
_RUN = os.environ[RUN_VARIABLE]
if _WORKER is not None and hasattr(os, "sched_setaffinity"):
    _cores = sorted(os.sched_getaffinity(0))
    if int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", len(_cores) + 1)) <= len(_cores):
        # modulo: xdist names a worker that replaces a crashed one with the next number
        os.sched_setaffinity(0, {_cores[int(_WORKER.removeprefix("gw")) % len(_cores)]})
_HOME = os.path.join(_RUN, f"home-{_WORKER or 'main'}")
os.makedirs(_HOME, mode=0o700, exist_ok=True)
os.environ[HOME_VARIABLE] = _HOME
os.environ[CACHE_VARIABLE] = os.path.join(_RUN, "cache")
os.environ["JAX_COMPILATION_CACHE_DIR"] = os.path.join(_RUN, "jax")
# every compiled function is worth keeping: most of the suite's compile in well under a second
os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0"
os.environ["JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES"] = "0"
_STARTED = time.monotonic()


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda item: item.get_closest_marker("long") is None)  # stable: long first


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    if _WORKER is not None or config.option.collectonly:
        return
    minutes = (time.monotonic() - _STARTED) / 60
    workers = getattr(config.option, "numprocesses", None) or 1
    budget = BUDGET_MINUTES.get(config.option.markexpr)
    line = f"this run: {minutes:.1f} min of wall time on {workers} worker(s)"
    if budget is not None:
        line += (f"; budget of `-m {config.option.markexpr!r}`: {budget} min on the project's "
                 "2-core machine" + ("" if minutes <= budget else
                                     " -- over: see the slowest tests above"))
    terminalreporter.write_sep("=", "time budget")
    terminalreporter.write_line(line)


def pytest_unconfigure(config):
    if _OWNER:
        shutil.rmtree(_RUN, ignore_errors=True)
