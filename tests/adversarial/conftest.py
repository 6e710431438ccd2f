"""The adversarial suite's shared parts: its helper module on ``sys.path`` (so that spawned
worker processes and fresh interpreters import it by name too) and a session tally of bounces,
escapes and bad inputs, printed at the end of the run."""

import os
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


@pytest.fixture(scope="session")
def tally(pytestconfig) -> Counter:
    """Counters the tests add to: ``bounces[<backend>]``, ``escapes``, ``nonfinite``, ``worlds``,
    ``bad inputs``; `pytest_terminal_summary` prints them."""
    return pytestconfig.stash.setdefault(_TALLY, Counter())


def pytest_terminal_summary(terminalreporter, exitstatus, config):
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
