"""Running a sweep of independent units of work — in this process, on a local process pool or
on Ray — with a store that keeps every finished unit, so that a sweep started again skips them.

A `Unit` is a module-level function and its (picklable) arguments under a key that is unique in
its sweep and the same in every run of it. `Executor.run` runs the units a `UnitStore` does not
hold yet, saves each result as soon as it arrives, and retries a unit whose worker died or that
raised, at most ``retries`` more times; a unit that fails for good is reported as a
`UnitFailure` while the others complete. Results come back by key: callers put them in their
own canonical order, so nothing depends on which worker finished first.

Executors (`make_executor`):

* ``local`` with one worker runs the units one after another in this process (no pickling, no
  new process; a crash of the unit is the crash of the program, whose stored units survive);
* ``local`` with more workers runs them on a ``concurrent.futures.ProcessPoolExecutor`` whose
  processes are started by a fork server (`POOL_START_METHOD`). A worker that dies breaks the
  whole pool: it is rebuilt, and the units that were in flight run again one at a time (the
  one whose worker died cannot be told apart otherwise), each attempt that then dies counting
  against its unit;
* ``ray`` runs each unit as a Ray task on a running cluster (``address``) or on a local instance
  started here (``num_cpus = workers``). Ray itself retries a task whose worker process died
  (``max_retries``); an exception is retried here. At most ``workers`` units are in flight.

**Numbers and addresses** (`executor_settings`): ``workers`` is an integer in
[1, `MAX_WORKERS` = 1024], ``retries`` in [0, `MAX_RETRIES` = 100]. A Ray ``address`` is
``auto`` (the cluster that ``RAY_ADDRESS`` names, else the one ``ray start`` recorded in
``<RAY_TMPDIR, TMPDIR or /tmp>/ray/ray_current_cluster``), ``host:port`` or ``ray://host:port``
(Ray Client), where the host is a host name, an IPv4 address or an IPv6 one in brackets and the
port is in 1..65535. Before Ray connects, `check_ray_cluster` gives the cluster
`CONNECT_TIMEOUT` (5) seconds to accept a TCP connection and answer as the gRPC (HTTP/2)
servers of Ray do (not checked on a cluster with ``RAY_USE_TLS`` set): an address where nothing
listens, or something else does, is a `ConfigError` in one line instead of Ray's minutes of
retries (docs/choices/worlds.md, "A Ray address must answer before Ray connects"); so is any failure of
``ray.init`` itself (`init_ray`).

Every executor keeps at most ``workers`` units in flight, so a pool that breaks or a cluster
that is lost loses no more than that.

The `UnitStore` signs every result it keeps with the user's key (`bounce_gym.trust`) and reads
back only what that key signed: a result file planted in or copied into the store is never
unpickled, only reported (one ``warning:`` line) and its unit run again.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ipaddress
import multiprocessing
import os
import pickle
import re
import shutil
import socket
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from bounce_gym.errors import ConfigError
from bounce_gym.extras import require
from bounce_gym.files import atomic_write, open_no_follow
from bounce_gym.trust import secret_key, sign, verify
from bounce_gym.validate import integer, unknown_keys

EXECUTOR_KINDS = ("local", "ray")
#: how the local pool starts its processes: never a fork of this one (which may hold threads:
#: tqdm's monitor, torch's pools), but forks of a clean server process, ~1 s faster per pool
#: than fresh interpreters ("spawn", where there is no forkserver) — docs/choices/studies.md
POOL_START_METHOD = ("forkserver" if "forkserver" in multiprocessing.get_all_start_methods()
                     else "spawn")
#: what a unit's error says when its process died instead of returning or raising
WORKER_DIED = "worker died"
_KEY = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.=+-]*")
#: a stored unit's file name ends so (`UnitStore`)
UNIT_SUFFIX = ".unit"
_UNIT_MAGIC = "bounce_gym-unit"


@dataclass(frozen=True)
class Unit:
    """One independent piece of a sweep: ``fn(*args)``. ``fn`` is a module-level function (a
    worker imports it by name) and ``key`` names the unit's stored result: unique in the sweep,
    the same in every run of it, and a file name (letters, digits and ``_.=+-``)."""

    key: str
    fn: Callable
    args: tuple = ()

    def __post_init__(self) -> None:
        if not _KEY.fullmatch(self.key):
            raise ValueError(f"unit key {self.key!r}: expected letters, digits and _.=+- "
                             "(not starting with . = + -)")


@dataclass
class UnitFailure:
    """A unit that failed for good: its key, its last error (the exception's type and message,
    or `WORKER_DIED`) and how many times it was tried."""

    key: str
    error: str
    attempts: int


class UnitStore:
    """Finished units' results, one file ``<key>.unit`` per unit in ``folder``, each written
    atomically (`bounce_gym.files.atomic_write`), so that a sweep interrupted at any instant
    leaves only whole results.

    A result is a pickle (rows and plot data of any kind), and unpickling runs whatever the file
    says; so each file is signed with the user's key (`bounce_gym.trust`, kept outside the
    output folder) and read back only if the signature holds. The file is one line
    ``bounce_gym-unit <hex HMAC-SHA256>`` and then the pickle; the signature covers the pickle,
    the unit's key and the folder's name (a sweep's fingerprint), so a file moved to another
    unit or sweep is not taken either. A file that is unsigned, signed with another key,
    changed, truncated or not a regular file is one ``warning:`` line on stderr and its unit
    runs again (`stored`); it is never unpickled, and its result replaces it (a folder planted
    at its name is removed, a link replaced, never followed). Results are signed where `Executor.run` saves
    them — the process that started the sweep — so workers (a pool, a Ray cluster) need no key.
    The key is read when the store is made, so a missing or unreadable key is reported before
    any unit runs."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        secret_key()  # made or read now: a problem with it is reported before any unit runs

    def _path(self, key: str) -> Path:
        return self.folder / f"{key}{UNIT_SUFFIX}"

    def _purpose(self, key: str) -> str:
        return f"unit {self.folder.name}/{key}"

    def save(self, key: str, result: object) -> None:
        data = pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)
        header = f"{_UNIT_MAGIC} {sign(data, self._purpose(key))}\n".encode()
        path = self._path(key)
        if path.is_dir() and not path.is_symlink():  # planted there, and reported (`stored`)
            try:
                shutil.rmtree(path)
            except OSError as exc:
                raise ConfigError(f"{path}: a folder planted at a unit's name cannot be removed "
                                  f"({exc.strerror or exc}); remove it") from None
        atomic_write(path, header + data)

    def load(self, key: str) -> object:
        """The stored result of unit ``key``; `FileNotFoundError` if there is none, and
        `StoredUnitError` if its file fails the check (class docstring)."""
        data = self._verified(key, _read_regular(self._path(key)))
        try:
            return pickle.loads(data)  # noqa: S301  (signed with the user's key)
        except Exception as exc:  # signed, but this code cannot rebuild it (e.g. a class moved)
            raise StoredUnitError(f"cannot be unpickled ({error_text(exc)})") from None

    def stored(self, keys: Iterable[str]) -> dict[str, object]:
        """The results of ``keys`` the store holds and vouches for; each file that fails the
        check is one warning line on stderr, and its unit is left out (to run again)."""
        out = {}
        for key in keys:
            try:
                out[key] = self.load(key)
            except FileNotFoundError:
                continue
            except (OSError, StoredUnitError) as exc:
                why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
                print(f"warning: {self._path(key)}: not taken as a unit result ({why}); "
                      "running the unit again", file=sys.stderr)
        return out

    def _verified(self, key: str, raw: bytes) -> bytes:
        head, newline, data = raw.partition(b"\n")
        magic, _, signature = head.partition(b" ")
        if not newline or magic != _UNIT_MAGIC.encode():
            raise StoredUnitError("not signed: no signature line")
        if not verify(data, signature.decode("ascii", "replace"), self._purpose(key)):
            raise StoredUnitError("its signature does not match your key: signed with "
                                  "another, or changed or cut short since")
        return data


class StoredUnitError(Exception):
    """A stored unit's file that is not taken (`UnitStore`): it fails the check, or, though
    signed, this code cannot unpickle it; the message says why."""


def _read_regular(path: Path) -> bytes:
    """The bytes of the regular file ``path``, never through a symbolic link nor waiting on a
    pipe planted at its name (`bounce_gym.files.open_no_follow`; `StoredUnitError`)."""
    try:
        fd = open_no_follow(path, os.O_RDONLY)
    except ConfigError as exc:
        raise StoredUnitError(str(exc).removeprefix(f"{path}: ")) from None
    with os.fdopen(fd, "rb") as fh:
        return fh.read()


def error_text(exc: BaseException) -> str:
    """An exception as a failure reports it: ``Type: message``."""
    return f"{type(exc).__name__}: {exc}"


class Executor:
    """Runs units (`run`); subclasses start them (`_submit`) and collect finished ones
    (`_finished`), at most `_slots` at a time."""

    def __init__(self, workers: int, retries: int) -> None:
        self.workers = workers
        self.retries = retries

    def run(self, units: Iterable[Unit], store: UnitStore, progress: bool = True,
            desc: str = "units") -> tuple[dict[str, object], list[UnitFailure]]:
        """Run every unit ``store`` does not hold (or holds in a file that fails its check,
        `UnitStore.stored`), saving each result as it finishes; returns every unit's result by
        key (stored ones included) and the units that failed for good, in the order given. One
        progress bar counts all units, stored ones from the start."""
        from tqdm import tqdm

        units = list(units)
        keys = [u.key for u in units]
        if len(set(keys)) != len(keys):
            twice = sorted({k for k in keys if keys.count(k) > 1})
            raise ValueError(f"unit keys must be unique in a sweep, repeated: {twice[:5]}")
        results = store.stored(keys)
        pending = [u for u in units if u.key not in results]
        failed: dict[str, UnitFailure] = {}
        with tqdm(total=len(units), initial=len(results), desc=desc, unit="unit",
                  disable=not progress) as bar:
            if pending:
                for unit, ok, value, attempts in self._attempts(pending):
                    if ok:
                        store.save(unit.key, value)
                        results[unit.key] = value
                    else:
                        failed[unit.key] = UnitFailure(unit.key, value, attempts)
                    bar.update()
        return results, [failed[k] for k in keys if k in failed]

    def _attempts(self, units: list[Unit]) -> Iterator[tuple[Unit, bool, object, int]]:
        """Each unit's final outcome ``(unit, ok, result or error text, attempts)``, as they
        finish, retrying failed attempts up to `retries` more times.

        An attempt lost together with others (a pool broken while several units ran) counts
        against none of them: they become suspects and run again one at a time, before any
        other unit, so that the one that kills its worker is charged and the others are not."""
        queue = list(reversed(units))  # pop() takes them in the order given
        tries: dict[str, int] = {}
        suspects: set[str] = set()
        in_flight: dict[object, Unit] = {}
        with self._session():
            while queue or in_flight:
                while queue and len(in_flight) < (1 if suspects else self._slots()):
                    unit = queue.pop()
                    tries[unit.key] = tries.get(unit.key, 0) + 1
                    in_flight[self._submit(unit)] = unit
                for handle, ok, value, used in self._finished(list(in_flight)):
                    unit = in_flight.pop(handle)
                    tries[unit.key] += used - 1
                    if used == 0:
                        suspects.add(unit.key)
                        queue.append(unit)
                        continue
                    suspects.discard(unit.key)
                    if ok or tries[unit.key] > self.retries:
                        yield unit, ok, value, tries[unit.key]
                    else:
                        queue.append(unit)

    def _slots(self) -> int:
        return self.workers

    def _session(self) -> contextlib.AbstractContextManager:
        """Around a run: start and stop the workers."""
        return contextlib.nullcontext()

    def _submit(self, unit: Unit) -> object:
        """Start one attempt of ``unit``; returns its handle."""
        raise NotImplementedError

    def _finished(self, handles: list) -> list[tuple[object, bool, object, int]]:
        """Wait until at least one of ``handles`` has finished; each finished one as
        ``(handle, ok, result or error text, attempts it took)``, where 0 attempts means lost
        with others through no known fault of its own."""
        raise NotImplementedError


class _Done:
    """The handle of an attempt that has already run (in-process)."""

    def __init__(self, ok: bool, value: object) -> None:
        self.ok, self.value = ok, value


class InProcessExecutor(Executor):
    """The units one after another in this process."""

    def __init__(self, retries: int) -> None:
        super().__init__(1, retries)

    def _submit(self, unit: Unit) -> _Done:
        try:
            return _Done(True, unit.fn(*unit.args))
        except Exception as exc:  # reported as the unit's failure; the others go on
            return _Done(False, error_text(exc))

    def _finished(self, handles: list) -> list[tuple[object, bool, object, int]]:
        return [(h, h.ok, h.value, 1) for h in handles]


class PoolExecutor(Executor):
    """The units on a pool of ``workers`` processes (`POOL_START_METHOD`); a pool broken by a
    dying worker is rebuilt and the units in flight are tried again."""

    def __init__(self, workers: int, retries: int) -> None:
        super().__init__(workers, retries)
        self._pool: cf.ProcessPoolExecutor | None = None

    @contextlib.contextmanager
    def _session(self) -> Iterator[None]:
        try:
            yield
        finally:
            if self._pool is not None:
                self._pool.shutdown(wait=True, cancel_futures=True)
                self._pool = None

    def _submit(self, unit: Unit) -> cf.Future:
        if self._pool is None:
            self._pool = cf.ProcessPoolExecutor(
                self.workers, mp_context=multiprocessing.get_context(POOL_START_METHOD),
                initializer=_one_thread)
        try:
            return self._pool.submit(unit.fn, *unit.args)
        except cf.process.BrokenProcessPool as exc:  # broke since the last wait: lost with it
            future = cf.Future()
            future.set_exception(exc)
            return future

    def _finished(self, handles: list) -> list[tuple[object, bool, object, int]]:
        done, _ = cf.wait(handles, return_when=cf.FIRST_COMPLETED)
        out, lost = [], []
        for future in done:
            exc = future.exception()
            if isinstance(exc, cf.process.BrokenProcessPool):
                lost.append(future)
            elif exc is not None:
                out.append((future, False, error_text(exc), 1))
            else:
                out.append((future, True, future.result(), 1))
        if lost:  # every unit in flight is lost with the pool: rebuild it on the next submit
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
            lost += [f for f in handles if f not in done]
            charged = 1 if len(lost) == 1 else 0  # alone, it is the one whose worker died
            out += [(f, False, WORKER_DIED, charged) for f in lost]
        return out


#: the variables torch reads its thread count from when it is imported (MKL's over OpenMP's)
_TORCH_THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _one_thread() -> None:
    """A pool worker's start: one torch thread per process (several processes share the
    cores); torch is set only if it is installed.

    Where torch is not imported yet and these variables (`_TORCH_THREAD_VARIABLES`) say one
    thread or nothing (``OMP_NUM_THREADS`` is set to 1 here unless the environment says
    otherwise), torch starts with one thread whenever a unit imports it, and it is not imported
    here: that import costs ~1.3 s of CPU per worker, for units that may never use torch."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    if "torch" not in sys.modules and all(os.environ.get(name, "1") == "1"
                                          for name in _TORCH_THREAD_VARIABLES):
        return
    try:
        import torch
    except ImportError:
        return
    torch.set_num_threads(1)


class RayExecutor(Executor):
    """The units as Ray tasks on the cluster at ``address``, or on a local instance with
    ``workers`` CPUs; a task whose worker process died is retried by Ray (``max_retries``), an
    exception here. A Ray already initialised in this process (e.g. by a test) is used as it
    is and left running."""

    def __init__(self, workers: int | None, address: str | None, retries: int) -> None:
        super().__init__(workers, retries)
        self.address = address
        self._task = None

    def _slots(self) -> int:
        return self.workers if self.workers is not None else 1 << 30

    @contextlib.contextmanager
    def _session(self) -> Iterator[None]:
        import ray

        started = init_ray("executor.address", self.address, self.workers)
        self._task = ray.remote(max_retries=self.retries, retry_exceptions=False)(_call)
        try:
            yield
        finally:
            self._task = None
            if started:
                ray.shutdown()

    def _submit(self, unit: Unit) -> object:
        return self._task.remote(unit.fn, unit.args)

    def _finished(self, handles: list) -> list[tuple[object, bool, object, int]]:
        import ray
        from ray.exceptions import RayError, RayTaskError, WorkerCrashedError

        done, _ = ray.wait(handles, num_returns=1)
        out = []
        for ref in done:
            try:
                out.append((ref, True, ray.get(ref), 1))
            except RayTaskError as exc:  # the unit raised: retried here
                cause = exc.cause if exc.cause is not None else exc
                out.append((ref, False, error_text(cause), 1))
            except WorkerCrashedError:  # Ray has retried it max_retries times already
                out.append((ref, False, WORKER_DIED, 1 + self.retries))
            except RayError as exc:  # e.g. a lost node or out of memory: retried here
                out.append((ref, False, error_text(exc), 1))
        return out


def _call(fn: Callable, args: tuple) -> object:
    """A Ray task: one attempt of a unit, with one torch thread."""
    _one_thread()
    return fn(*args)


def machine_cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


#: an ``executor`` block's keys and defaults (``workers: None``: see `make_executor`)
EXECUTOR_DEFAULTS = {"kind": "local", "workers": None, "address": None, "retries": 2}
#: the most units at once, and retries of a unit (module docstring)
MAX_WORKERS = 1024
MAX_RETRIES = 100
#: seconds a Ray cluster has to answer `check_ray_cluster`
CONNECT_TIMEOUT = 5.0
#: what a Ray address may be, in words
RAY_ADDRESSES = "auto, host:port or ray://host:port"
_HOST_NAME = re.compile(r"(?!-)[A-Za-z0-9-]{1,63}(?<!-)(\.(?!-)[A-Za-z0-9-]{1,63}(?<!-))*\.?")
#: the first bytes of an HTTP/2 connection (RFC 9113, 3.4), then an empty SETTINGS frame
_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
_SETTINGS_FRAME = 4


def executor_settings(value: object, where: str = "executor",
                      names: Mapping[str, str] | None = None) -> dict:
    """An ``executor`` block (``{kind, workers, address, retries}``, every key optional)
    checked and completed with `EXECUTOR_DEFAULTS`; a mistake raises `ConfigError` naming
    ``<where>.<key>``, or ``names[key]`` (e.g. a command-line flag)."""
    names = names or {}

    def field(key: str) -> str:
        return names.get(key, f"{where}.{key}")

    if not isinstance(value, Mapping):
        raise ConfigError(f"{where}: expected a mapping {{kind, workers, address, retries}}, "
                          f"got {type(value).__name__}")
    unknown_keys(where, value, EXECUTOR_DEFAULTS)
    out = {**EXECUTOR_DEFAULTS, **value}
    if out["kind"] not in EXECUTOR_KINDS:
        raise ConfigError(f"{field('kind')}: expected one of {EXECUTOR_KINDS}, got "
                          f"{out['kind']!r}")
    if out["workers"] is not None:
        integer(field("workers"), out["workers"], 1, MAX_WORKERS)
    integer(field("retries"), out["retries"], 0, MAX_RETRIES)
    if out["address"] is not None:
        if out["kind"] != "ray":
            raise ConfigError(f"{field('address')}: only for the ray executor "
                              f"({field('kind')}: ray)")
        ray_endpoint(field("address"), out["address"])
    return out


def ray_endpoint(field: str, address: object) -> tuple[str, int] | None:
    """The host and port of a Ray address (module docstring), None for ``auto``; a
    `ConfigError` naming ``field`` if it is none."""
    if address == "auto":
        return None
    rest = address.removeprefix("ray://") if isinstance(address, str) else ""
    host, _, port = rest.rpartition(":")
    if not (port.isascii() and port.isdigit() and 1 <= int(port) <= 65535 and _is_host(host)):
        raise ConfigError(f"{field}: expected a Ray address ({RAY_ADDRESSES}; a host name or "
                          f"IP address, a port in 1..65535), got {address!r}")
    return host.strip("[]"), int(port)


def _is_host(host: str) -> bool:
    """Whether ``host`` is an IPv4 address, an IPv6 address in brackets, or a host name (whose
    last label is not all digits, so 256.1.1.1 is no name)."""
    if host.startswith("[") and host.endswith("]"):
        try:
            ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            return False
        return True
    if host.replace(".", "").isdigit():
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            return False
        return True
    return len(host) <= 253 and bool(_HOST_NAME.fullmatch(host)) \
        and not host.rstrip(".").rsplit(".", 1)[-1].isdigit()


def check_ray_cluster(field: str, address: str) -> None:
    """Raise `ConfigError` naming ``field`` unless a Ray cluster answers at ``address``
    within `CONNECT_TIMEOUT` seconds (module docstring); ``auto`` is the cluster that
    ``RAY_ADDRESS`` or ``ray start`` named."""
    endpoint = ray_endpoint(field, address)
    if endpoint is None:
        found, source = _auto_address()
        if found is None:
            raise ConfigError(f"{field}: auto: no running Ray cluster found ({source}); start "
                              "one with `ray start --head`, or give its host:port")
        endpoint = ray_endpoint(f"{field} (auto, from {source})", found)
        address = found
    try:
        with socket.create_connection(endpoint, timeout=CONNECT_TIMEOUT) as connection:
            if os.environ.get("RAY_USE_TLS", "0").lower() in ("0", "false", ""):
                connection.sendall(_HTTP2_PREFACE)
                answer = connection.recv(9, socket.MSG_WAITALL)  # a frame header
                if len(answer) < 9 or answer[3] != _SETTINGS_FRAME:
                    raise ConfigError(f"{field}: {address!r} is not a Ray cluster: it does not "
                                      "answer as Ray's gRPC servers do")
    except TimeoutError:
        raise ConfigError(f"{field}: no Ray cluster answers at {address!r} within "
                          f"{CONNECT_TIMEOUT:g} s") from None
    except OSError as exc:
        raise ConfigError(f"{field}: cannot reach a Ray cluster at {address!r}: "
                          f"{exc.strerror or exc}") from None


def _auto_address() -> tuple[str | None, str]:
    """The address ``auto`` stands for, and where it was found (or looked for)."""
    if os.environ.get("RAY_ADDRESS", "auto") != "auto":
        return os.environ["RAY_ADDRESS"], "RAY_ADDRESS"
    temp = os.environ.get("RAY_TMPDIR") or os.environ.get("TMPDIR") or "/tmp"
    path = Path(temp) / "ray" / "ray_current_cluster"
    if not path.is_file():
        return None, f"RAY_ADDRESS names none and {path} does not exist"
    return path.read_text(encoding="utf-8", errors="replace").strip(), str(path)


def init_ray(field: str, address: str | None, workers: int | None, **options) -> bool:
    """Connect to the Ray cluster at ``address`` (after `check_ray_cluster`), or start a local
    instance with ``workers`` CPUs (``options``: more `ray.init` arguments for it), unless Ray
    is initialised in this process already; returns whether it was initialised here (and is
    to be shut down). A failure is a `ConfigError` naming ``field``, in one line."""
    import ray

    if ray.is_initialized():
        return False
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # no network call home
    if address is not None:
        check_ray_cluster(field, address)
    try:
        if address is None:
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False, **options)
        else:
            ray.init(address=address, log_to_driver=False)
    except (ConnectionError, RuntimeError, TimeoutError, ValueError) as exc:
        line = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        where = f"the Ray cluster at {address!r}" if address else "a local Ray instance"
        raise ConfigError(f"{field}: cannot start or reach {where}: {line}") from None
    return True


def make_executor(kind: str = "local", workers: int | None = None, address: str | None = None,
                  retries: int = 2) -> Executor:
    """The executor ``kind`` (``local`` or ``ray``; module docstring). ``workers``: units run
    at once (default: the machine's cores for ``local`` and a local Ray, no limit on a
    cluster); ``address``: a Ray cluster's (only for ``ray``; default: start a local
    instance); ``retries``: attempts after a unit's first failure. Arguments are checked as
    an ``executor`` block (`executor_settings`)."""
    executor_settings(dict(kind=kind, workers=workers, address=address, retries=retries))
    if kind == "local":
        workers = machine_cores() if workers is None else workers
        return InProcessExecutor(retries) if workers == 1 else PoolExecutor(workers, retries)
    require("executor: ray", "ray")
    if workers is None and address is None:
        workers = machine_cores()
    return RayExecutor(workers, address, retries)
