"""Interleaved rounds: every timed callable runs once per round, in turn, so that the load of a
shared machine hits all of them alike; ratios are then taken within a round."""

from __future__ import annotations

import statistics
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


def ratio(per_round: list[float], target: float | None) -> dict:
    """A ratio's median, min and max over the rounds, with its ``target`` (None: reported)."""
    return dict(median=statistics.median(per_round), low=min(per_round), high=max(per_round),
                target=target)


def verdict(row: dict) -> str:
    """``"  ok"`` or ``"  below target"`` for a `ratio` row with a target, else ``""``."""
    if row["target"] is None:
        return ""
    return "  ok" if row["median"] >= row["target"] else "  below target"
