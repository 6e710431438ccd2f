"""The adversarial suite's shared parts: its helper module on ``sys.path`` (so that spawned
worker processes and fresh interpreters import it by name too) and a session tally of bounces,
escapes and bad inputs, printed at the end of the run."""

import os
import statistics
import sys
from collections import Counter
from pathlib import Path

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

_TALLY = pytest.StashKey[Counter]()
_RECORDS = pytest.StashKey[list]()


@pytest.fixture(scope="session")
def tally(pytestconfig) -> Counter:
    """Counters the tests add to: ``bounces[<backend>]``, ``escapes``, ``nonfinite``, ``worlds``,
    ``bad inputs``; `pytest_terminal_summary` prints them."""
    return pytestconfig.stash.setdefault(_TALLY, Counter())


@pytest.fixture(scope="session")
def hostile_records(pytestconfig) -> list:
    """What each case of the hostile-input suite took: ``(class:name, mode, CPU seconds,
    memory bytes)``, mode ``in-process`` or ``subprocess``; `pytest_terminal_summary` sums
    them up."""
    return pytestconfig.stash.setdefault(_RECORDS, [])


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    _hostile_summary(terminalreporter, config.stash.get(_RECORDS, []))
    counts = config.stash.get(_TALLY, None)
    if not counts:
        return
    bounces = {k.split(":", 1)[1]: v for k, v in counts.items() if k.startswith("bounces:")}
    terminalreporter.section("adversarial suite")
    terminalreporter.write_line(
        "bounces per backend: " + ", ".join(f"{k} {v:,}" for k, v in sorted(bounces.items()))
        + f" (total {sum(bounces.values()):,})")
    terminalreporter.write_line(
        f"escapes {counts['escapes']}, non-finite states {counts['nonfinite']}, "
        f"worlds {counts['worlds']}, bad inputs {counts['bad inputs']:,}")


def _hostile_summary(reporter, records: list) -> None:
    """The hostile-input suite's cases per class, and their CPU time and peak memory."""
    if not records:
        return
    reporter.section("hostile inputs")
    for mode in ("in-process", "subprocess"):
        mine = [r for r in records if r[1] == mode]
        if not mine:
            continue
        per_class = Counter(r[0].split(":", 1)[0] for r in mine)
        slowest = max(mine, key=lambda r: r[2])
        largest = max(mine, key=lambda r: r[3])
        reporter.write_line(f"{mode}: {len(mine)} cases: " + ", ".join(
            f"{cls} {n}" for cls, n in per_class.items()))
        reporter.write_line(
            f"  CPU per case: median {statistics.median(r[2] for r in mine):.3f} s, max "
            f"{slowest[2]:.3f} s ({slowest[0]}); peak memory: max {largest[3] / 2**20:.0f} MiB "
            f"({largest[0]}; " + ("growth of the peak resident memory)" if mode == "in-process"
                                  else "ru_maxrss of the child, start-up included)"))
