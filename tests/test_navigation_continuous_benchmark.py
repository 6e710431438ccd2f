"""The continuous-angle navigation benchmark: the commands docs/continuous_planners.md gives run
(two episodes each) and print what the page quotes."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from benchmarks import navigation_continuous

ROOT = Path(__file__).parents[1]
PROGRAM = "python -m benchmarks.navigation_continuous"


def _documented() -> list[str]:
    text = (ROOT / "docs" / "continuous_planners.md").read_text(encoding="utf-8")
    return sorted({" ".join(c.split()) for c in re.findall(
        r"`(python -m benchmarks\.navigation_continuous[^`]*)`", text)})


def test_the_page_gives_the_noise_free_and_the_noisy_command():
    commands = _documented()
    assert PROGRAM in commands and f"{PROGRAM} --noise" in commands


@pytest.mark.parametrize("command", _documented())
def test_documented_command_runs(command, capsys):
    argv = shlex.split(command.removeprefix(PROGRAM)) + ["--episodes", "2",
                                                         "--first-seed", "10002"]
    rows = navigation_continuous.main(argv)
    assert len(rows) == 2
    assert all(0.0 <= r["predicted"] <= 1.0 and r["seconds"] > 0 for r in rows)
    printed = capsys.readouterr().out
    for label in ("cell-feasible", "world-reachable", "planner time per episode"):
        assert label in printed
