"""The sampled-GCM navigation benchmark runs end to end, and so does every command line of it
that the docs pages give, verbatim but for a small budget appended (argparse keeps the last
value of a repeated option)."""

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from benchmarks import navigation_sampled

ROOT = Path(__file__).parents[1]
PAGES = ("docs/sampled_models.md", "docs/continuous_planners.md")
PROGRAM = "python -m benchmarks.navigation_sampled"
#: the budget appended to each documented command
BUDGET = ["--episodes", "2", "--samples", "2", "--depth", "1", "--reach", "3",
          "--cell-size", "1", "--particles", "4", "--draws", "16"]


def _documented() -> list[str]:
    found = []
    for page in PAGES:
        text = (ROOT / page).read_text(encoding="utf-8")
        for quoted in re.findall(r"`(python -m benchmarks\.navigation_sampled[^`]*)`", text):
            found.append(" ".join(quoted.split()))
    return sorted(set(found))


def test_the_docs_give_the_noise_free_noisy_and_dynamic_commands():
    commands = _documented()
    assert PROGRAM in commands
    assert any("--noise" in c and "pymunk" not in c for c in commands)
    assert any("--physics dynamic" in c and "--noise" in c for c in commands)


@pytest.mark.parametrize("command", [
    pytest.param(c, marks=pytest.mark.slow) if "pymunk" in c else c for c in _documented()])
def test_documented_command_runs(command, capsys):
    """(The dynamic-physics command builds its model on pymunk: about half a minute, so it runs
    with the slow tests.)"""
    argv = shlex.split(command.removeprefix(PROGRAM)) + BUDGET
    out = navigation_sampled.main(argv)
    assert len(out["sampled"]) == 2 and len(out["roadmap"]) == 2
    assert np.all((out["predicted"] >= 0) & (out["predicted"] <= 1))
    printed = capsys.readouterr().out
    assert "sampled SSP + filter" in printed
    assert ("upper bound" in printed) == ("--noise" not in command)
