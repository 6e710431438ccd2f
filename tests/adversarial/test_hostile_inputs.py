"""Issue 22's hostile-input suite: malformed configurations, maps, flow files, model files,
unit files, flags, environment variables, actions and env arguments, fed to the ``bounce-gym``
command (and its wrappers ``evaluate.py`` and ``train.py``) and to the Python API (the
catalogue: `hostile_cases`, `hostile_files`, `hostile_api`).

Each command-line case runs in a case folder two levels below the test's temporary folder, in
this process (``bounce_gym_experiments.cli.main``), and must end with

* exit status 2 and exactly one line on stderr, ``error: ...`` containing what the case
  expects, nothing on stdout, no traceback (a Python warning counts as lines on stderr) — or,
  for a unit file planted in an evaluation's store (class ``units``), exit status 0 after
  ``warning:`` lines naming it (the unit runs again), and for a model file whose planted
  pickles are never read (class ``loads``), exit status 0 and nothing on stderr;
* nothing created, changed or removed in the temporary folder outside the output folder the
  case names (the user's bounce_gym folder, ``$BOUNCE_GYM_HOME``, lies elsewhere and may gain
  its key);
* no marker file: no payload ran (pickles with ``__reduce__``, YAML tags calling
  ``os.system``);
* **CPU**: under `CPU_BOUND` (1 s) of this process's CPU time (``time.process_time``) after
  start-up: the imports are warmed first by a valid evaluation, a model trained and loaded, a
  flow file read and every env made once (`warmed`), and the objects they left are frozen
  for the garbage collector (`measure`);
* **memory**: the process's peak resident memory (``VmHWM``, reset before each case through
  ``/proc/self/clear_refs``) at most `MEMORY_BOUND` (256 MiB) above its resident memory
  before the case.

Every Python API case must raise its `bounce_gym.errors.BounceGymError` subclass with a
one-line message, within the same CPU and memory bounds and with the same checks on files and
markers. A subset of the command-line cases, a few of every class, runs again as real
processes (``python -m bounce_gym_experiments.cli``) that must exit 2 with one ``error:`` line and no
traceback (0 with warnings, for unit files), each within `CHILD_MEMORY_BOUND` (1.5 GiB) of
peak resident memory (``ru_maxrss`` of the child, from ``wait4``).

The counts per class, the CPU time per case (median and max) and the peak memory are printed
at the end of the run (the folder's conftest).
"""

from __future__ import annotations

import functools
import gc
import importlib.util
import io
import os
import re
import subprocess
import sys
import tempfile
import time
import warnings
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

import hostile_api
import hostile_cases
import hostile_files
import pytest
from hostile_cases import Case, Sandbox

from bounce_gym.errors import BounceGymError
from bounce_gym_experiments.cli import main

ROOT = Path(__file__).resolve().parents[2]
#: CPU seconds a case may take after start-up
CPU_BOUND = 1.0
#: growth of the peak resident memory a case may cause, in bytes
MEMORY_BOUND = 256 << 20
#: peak resident memory of a command run as its own process, in bytes
CHILD_MEMORY_BOUND = 1536 << 20
#: cases of each class run again as their own processes
PER_CLASS = 4

CLI_CASES = [*hostile_cases.cases(), *hostile_files.cases()]
API_CASES = hostile_api.cases()


def _spread(cases: list, n: int) -> list:
    """``n`` cases spread over the list (all if it has no more)."""
    step = max(len(cases) // n, 1)
    return cases[::step][:n]


CHILD_CASES = [case for cls in dict.fromkeys(c.cls for c in CLI_CASES)
               for case in _spread([c for c in CLI_CASES if c.cls == cls], PER_CLASS)]


# -- measuring -------------------------------------------------------------------------------
def _status_kib(field: str) -> int:
    text = Path("/proc/self/status").read_text()
    return int(re.search(rf"^{field}:\s+(\d+) kB", text, re.MULTILINE).group(1))


def _reset_peak() -> int:
    """Reset this process's peak resident memory to the present one; returns it (bytes)."""
    Path("/proc/self/clear_refs").write_text("5")
    return _status_kib("VmRSS") << 10


@dataclass
class Measured:
    """What a case did: its outcome, its CPU seconds and the growth of peak memory (bytes)."""

    outcome: object
    cpu: float
    memory: int


def measure(call) -> Measured:
    """Run ``call()``; its value, or the `BounceGymError` it raised (any other exception
    propagates), with the CPU time and the peak memory it took. The objects the test process
    holds already (pytest's, the warmed imports') are frozen meanwhile (``gc.freeze``): the
    garbage collector's passes over them are start-up, which a command's own process has far
    less of, not the case's cost."""
    gc.freeze()
    before = _reset_peak()
    start = time.process_time()
    try:
        outcome = call()
    except BounceGymError as exc:
        outcome = exc
    finally:
        cpu = time.process_time() - start
        gc.unfreeze()
    return Measured(outcome, cpu, (_status_kib("VmHWM") << 10) - before)


@dataclass
class Ran:
    status: int
    out: str
    err: str


#: the thin wrappers of the command, in the checkout's top folder
WRAPPERS = ("evaluate.py", "train.py")


@functools.cache
def wrapper(name: str):
    """The module of a wrapper (`WRAPPERS`), imported from its file."""
    spec = importlib.util.spec_from_file_location(name.removesuffix(".py"), ROOT / name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def in_process(argv: list[str]) -> Ran:
    """``bounce-gym <argv>`` (or the wrapper ``argv[0]`` names) in this process (exceptions
    other than its exit propagate). Python warnings are added to stderr as a process of its
    own would show them (Python's default filters: every warning but deprecations, import and
    resource warnings), not as pytest collects them."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err), \
            warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                         ResourceWarning):
            warnings.simplefilter("ignore", category)
        try:
            if argv[:1] and argv[0] in WRAPPERS:
                status = wrapper(argv[0]).main(argv[1:])
            else:
                status = main(argv)
        except SystemExit as exc:
            status = exc.code
    shown = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno)
                    for w in caught)
    return Ran(status, out.getvalue(), shown + err.getvalue())


def snapshot(root: Path) -> dict[str, tuple]:
    """Every entry below ``root`` (links not followed): its kind, and a file's size, time of
    change and inode; a folder's content is its entries."""
    out = {}
    for folder, names, files in os.walk(root):
        for name in names + files:
            path = os.path.join(folder, name)
            info = os.lstat(path)
            kind = info.st_mode >> 12
            key = (kind,) if os.path.isdir(path) and not os.path.islink(path) else (
                kind, info.st_size, info.st_mtime_ns, info.st_ino)
            out[os.path.relpath(path, root)] = key
    return out


def changed_outside(before: dict, after: dict, allowed: str) -> list[str]:
    """The entries created, changed or removed that are not ``allowed`` or below it."""
    changes = {p for p in before.keys() | after.keys() if before.get(p) != after.get(p)}
    return sorted(p for p in changes if p != allowed and not p.startswith(allowed + os.sep))


# -- fixtures --------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def trained(tmp_path_factory) -> Path:
    """A model this package trained (with its final checkpoint)."""
    from baselines.rl.train import train

    models = tmp_path_factory.mktemp("hostile-trained")
    config = {**hostile_cases.training(models=str(models)), "hyperparams": {
        "n_steps": 32, "batch_size": 32, "n_epochs": 1, "learning_rate": "lin_0.001",
        "policy_kwargs": {"activation_fn": "relu", "net_arch": [16]}}}
    (path,) = train(config, progress=False)
    return path


@pytest.fixture(scope="session")
def warmed(tmp_path_factory, trained) -> None:
    """Start-up: the imports of a valid evaluation, of loading a model (and a JAX learner's,
    where JAX is installed) and a flow file, and of every env, made before any case is
    measured."""
    import gymnasium as gym
    import pettingzoo

    from baselines.rl.model_files import read_model
    from bounce_gym.flows.netcdf import load_flow

    folder = tmp_path_factory.mktemp("hostile-warm")
    box = Sandbox(folder, folder / "MARKER")
    box.yaml("c.yaml", hostile_cases.evaluation(output=str(folder / "out")))
    assert in_process(["evaluate", str(folder / "c.yaml"), "--no-progress"]).status == 0
    env = gym.make(hostile_cases.NAVIGATION, **hostile_cases.NAV)
    read_model(trained).load(env.observation_space, env.action_space)
    if importlib.util.find_spec("jax") is not None:
        from baselines.rl.jaxrl.policy import JaxPolicy

        path = folder / "jax_ppo_seed0.zip"
        path.write_bytes(hostile_files.jax_model(hostile_files.jax_npz()))
        JaxPolicy(path, env)
    load_flow(hostile_files.flow_file(folder / "f.nc"))
    for env_id in hostile_api.GYM_IDS:
        gym.make(env_id).reset(seed=0)
    for env_id in hostile_api.PETTING_IDS:
        for kind in ("aec", "parallel"):
            pettingzoo.make(kind, env_id).reset(seed=0)


@pytest.fixture
def box(tmp_path, monkeypatch, request) -> Sandbox:
    """The case folder, two levels below the test's temporary folder, as the working folder."""
    here = tmp_path / "a" / "b" / "case"
    here.mkdir(parents=True)
    monkeypatch.chdir(here)
    return Sandbox(here, tmp_path / "MARKER")


def _prepare(case, box: Sandbox, request, monkeypatch):
    if case.cls in hostile_files.MODEL_CLASSES:
        box.trained = request.getfixturevalue("trained")
    for name, value in getattr(case, "env", ()):
        if value is None:
            monkeypatch.delenv(name, raising=False)
        else:
            monkeypatch.setenv(name, value.format(here=box.here))
    return case.build(box)


def _record(request, case, mode: str, cpu: float, memory: int) -> None:
    request.getfixturevalue("tally")["bad inputs"] += 1
    request.getfixturevalue("hostile_records").append((case.id, mode, cpu, memory))


def _no_trace(box: Sandbox, root: Path, before: dict, allowed: str) -> None:
    assert not box.marker.exists(), "a payload ran"
    assert not list(root.rglob("*MARKER*")), "a payload ran"
    outside = changed_outside(before, snapshot(root), allowed)
    assert not outside, f"changed outside {allowed}: {outside[:10]}"


def _check_output(case: Case, ran: Ran, box: Sandbox) -> None:
    assert "Traceback" not in ran.err, ran.err
    lines = ran.err.splitlines()
    if case.status == 2:
        assert ran.status == 2, (ran.status, ran.err[-2000:])
        assert len(lines) == 1 and lines[0].startswith("error: "), ran.err[-2000:]
        assert case.expect in lines[0], lines[0]
        assert ran.out == "", ran.out[-2000:]
    else:  # warnings naming the input (none for a file that is read as data)
        assert ran.status == 0, ran.err[-2000:]
        assert bool(lines) == bool(case.expect), ran.err
        assert all(line.startswith("warning: ") and case.expect in line for line in lines), \
            ran.err
        from bounce_gym_experiments.run_folders import finished_runs

        assert len(finished_runs(box.here / "out/runs")) == 1


# -- the cases -------------------------------------------------------------------------------
@pytest.mark.timeout(120)  # a hang guard only
@pytest.mark.parametrize("case", CLI_CASES, ids=lambda c: c.id)
def test_a_hostile_command_is_refused_in_one_line(case, box, tmp_path, request, monkeypatch,
                                                  warmed):
    argv = _prepare(case, box, request, monkeypatch)
    before = snapshot(tmp_path)
    done = measure(lambda: in_process(argv))
    _check_output(case, done.outcome, box)
    _no_trace(box, tmp_path, before, str(Path("a/b/case") / case.writes))
    _record(request, case, "in-process", done.cpu, done.memory)
    assert done.cpu < CPU_BOUND, f"{done.cpu:.2f} s of CPU"
    assert done.memory < MEMORY_BOUND, f"{done.memory >> 20} MiB"


@pytest.mark.timeout(120)
@pytest.mark.parametrize("case", API_CASES, ids=lambda c: c.id)
def test_a_hostile_call_raises_the_package_error(case, box, tmp_path, request, monkeypatch,
                                                 warmed):
    call = _prepare(case, box, request, monkeypatch)
    before = snapshot(tmp_path)
    done = measure(call)
    error = done.outcome
    assert isinstance(error, case.error), f"accepted, returning {error!r}"
    assert "\n" not in str(error) and case.expect in str(error), str(error)
    _no_trace(box, tmp_path, before, str(Path("a/b/case") / "out"))
    _record(request, case, "in-process", done.cpu, done.memory)
    assert done.cpu < CPU_BOUND, f"{done.cpu:.2f} s of CPU"
    assert done.memory < MEMORY_BOUND, f"{done.memory >> 20} MiB"


def run_child(argv: list[str], cwd: Path, timeout: float = 120) -> tuple[Ran, float, int]:
    """``python -m bounce_gym_experiments.cli <argv>`` (or ``python <wrapper> <argv[1:]>``) as its own
    process: what it printed, its CPU seconds (start-up included) and its peak resident memory
    (bytes)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        command = [str(ROOT / argv[0]), *argv[1:]] if argv[:1] and argv[0] in WRAPPERS \
            else ["-m", "bounce_gym_experiments.cli", *argv]
        child = subprocess.Popen([sys.executable, *command], cwd=cwd, stdout=out, stderr=err,
                                 env=env)
        deadline = time.monotonic() + timeout
        while True:
            pid, status, usage = os.wait4(child.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() > deadline:
                child.kill()
                child.wait()
                pytest.fail(f"still running after {timeout} s")
            time.sleep(0.01)
        child.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        ran = Ran(child.returncode, out.read().decode(errors="replace"),
                  err.read().decode(errors="replace"))
    return ran, usage.ru_utime + usage.ru_stime, usage.ru_maxrss << 10


@pytest.mark.timeout(180)
@pytest.mark.parametrize("case", CHILD_CASES, ids=lambda c: c.id)
def test_a_hostile_command_as_its_own_process(case, box, tmp_path, request, monkeypatch):
    argv = _prepare(case, box, request, monkeypatch)
    before = snapshot(tmp_path)
    ran, cpu, memory = run_child(argv, box.here)
    _check_output(case, ran, box)
    _no_trace(box, tmp_path, before, str(Path("a/b/case") / case.writes))
    _record(request, case, "subprocess", cpu, memory)
    assert memory < CHILD_MEMORY_BOUND, f"{memory >> 20} MiB"


def test_the_suite_is_as_large_as_the_issue_asks():
    assert len(CLI_CASES) + len(API_CASES) >= 200
    assert len(CHILD_CASES) >= 30
    assert len({c.id for c in [*CLI_CASES, *API_CASES]}) == len(CLI_CASES) + len(API_CASES)


# -- faults of the machine (issue 36, item 4) ------------------------------------------------
def _fill_the_disk(monkeypatch, after: str = "") -> None:
    """The temporary files the package writes (``bounce_gym.files``) are /dev/full from now on
    — only those whose name contains ``after``, if given — so their writes fail with ENOSPC,
    as on a full disk."""
    from bounce_gym import files

    real = files._no_follow

    def opener(path: str, flags: int) -> int:
        name = os.path.basename(path)
        if name.startswith(".") and name.endswith(".tmp") and after in name \
                and flags & (os.O_WRONLY | os.O_RDWR):
            return os.open("/dev/full", os.O_RDWR)
        return real(path, flags)
    monkeypatch.setattr(files, "_no_follow", opener)


FULL_DISK = [  # (command, the file whose write fails, where it lies)
    (["evaluate", "c.yaml", "--no-progress"], "", "out/runs/run-units"),
    (["evaluate.py", "c.yaml", "--no-progress"], "", "out/runs/run-units"),
    (["evaluate", "c.yaml", "--no-progress"], "summary.csv", "out/runs/run-"),
    (["evaluate", "c.yaml", "--no-progress"], ".png", "out/runs/run-"),
    (["train.py", "t.yaml", "--no-progress"], "monitor.csv", "out/models/nav"),
    (["train", "t.yaml", "--no-progress"], "_seed0.zip", "out/models/nav/ppo_seed0.zip"),
]


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("argv", "after", "where"), FULL_DISK,
                         ids=[f"{a[0]} {f or 'first write'}" for a, f, _ in FULL_DISK])
def test_a_full_disk_is_one_error_line_and_leaves_no_partial_file(argv, after, where, box,
                                                                   tmp_path, monkeypatch):
    box.yaml("c.yaml", hostile_cases.evaluation(experiment(policies=["random", "fixed"])))
    box.yaml("t.yaml", hostile_cases.training())
    _fill_the_disk(monkeypatch, after)
    ran = in_process(argv)
    assert "Traceback" not in ran.err, ran.err
    lines = ran.err.splitlines()
    assert ran.status == 2, ran.err[-2000:]
    assert len(lines) == 1 and lines[0].startswith("error: "), ran.err[-2000:]
    assert lines[0].endswith(": cannot write it: No space left on device"), lines[0]
    assert f"{where}" in lines[0] and after in lines[0], lines[0]
    written = [p for p in (box.here / "out").rglob("*") if p.is_file()]
    partial = [p for p in written if ".tmp" in str(p.relative_to(box.here))]
    assert partial == [], partial  # no temporary file left, none renamed into place
    assert not [p for p in (box.here / "out").glob("runs/run-*") if p.name != "run-units"]


def experiment(**overrides) -> dict:
    return hostile_cases.experiment(**overrides)
