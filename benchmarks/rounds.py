"""Interleaved rounds: every timed callable runs once per round, in turn, so that the load of a
shared machine hits all of them alike; ratios are then taken within a round."""

from __future__ import annotations

from collections.abc import Callable


def interleaved(runs: dict[str, Callable[[], float]], rounds: int) -> dict[str, list[float]]:
    """The value (a rate) each of ``runs`` returns in each of ``rounds`` rounds."""
    rates: dict[str, list[float]] = {label: [] for label in runs}
    for _ in range(rounds):
        for label, run in runs.items():
            rates[label].append(run())
    return rates


def spread(values: list[float], fmt: str) -> str:
    """``min–max`` of ``values`` in format ``fmt``."""
    return f"{min(values):{fmt}}–{max(values):{fmt}}"
