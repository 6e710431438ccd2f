"""Learning curves: what the monitor files of a models folder say about each run, per seed and
across seeds.

Every ``<run>_seed<seed>.monitor.csv`` of a folder (`baselines.rl.monitor`) is one seed of run
``<run>`` (``ppo``, ``ppo-stack4``, …). A metric is the return (``r``) or an outcome the env
reports (``is_success``, ``localized``, ``coverage``), smoothed as SB3 logs ``ep_rew_mean``: the
mean over the last ``window`` episodes, placed at the env steps at which the last of them ended
(SB3's count: the cumulative episode lengths). Across seeds, each smoothed curve is read at
common env steps (linear interpolation, up to where the shortest seed ends) and summarised by
its mean and a 95% confidence interval of the mean, Student's t with n − 1 degrees of freedom
(none for one seed).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from baselines.rl.monitor import SUFFIX, read_monitor
from bounce_gym.errors import ConfigError

#: Episodes in the moving mean (as SB3's ``ep_rew_mean``).
WINDOW = 100
#: Points of the across-seed curves.
POINTS = 200
_MONITOR = re.compile(r"(?P<run>[a-z0-9_-]+)_seed(?P<seed>\d+)" + re.escape(SUFFIX))
#: Monitor columns that are metrics, and their names in tables and plots.
METRICS = {"r": "return", "is_success": "success", "localized": "localized",
           "coverage": "coverage"}


@dataclass
class RunCurves:
    """One run's curves: per seed, the env steps and each smoothed metric."""

    name: str
    seeds: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)

    @property
    def metrics(self) -> list[str]:
        """The metrics every seed has, in `METRICS` order."""
        return [m for m in METRICS.values()
                if all(m in columns for columns in self.seeds.values())]

    def across_seeds(self, metric: str, points: int = POINTS):
        """``(steps, mean, low, high)`` of ``metric`` at common env steps; ``low``/``high``
        are the 95% interval of the mean (NaN for one seed)."""
        # Student's t quantile (what scipy.stats.t.ppf computes, without importing
        # scipy.stats: half a second of every training run's curves)
        from scipy.special import stdtrit

        end = min(columns["steps"][-1] for columns in self.seeds.values())
        steps = np.linspace(0.0, end, points)
        values = np.array([np.interp(steps, c["steps"], c[metric], left=np.nan)
                           for c in self.seeds.values()])
        n = values.shape[0]
        with np.errstate(invalid="ignore"):
            mean = values.mean(axis=0)
            if n < 2:
                return steps, mean, np.full_like(mean, np.nan), np.full_like(mean, np.nan)
            half = stdtrit(n - 1, 0.975) * values.std(axis=0, ddof=1) / np.sqrt(n)
        return steps, mean, mean - half, mean + half

    def final(self, seed: int) -> dict[str, float]:
        """The end point of one seed: episodes, env steps, each metric's last smoothed value."""
        columns = self.seeds[seed]
        return {"episodes": int(columns["episodes"]), "env_steps": int(columns["steps"][-1]),
                **{m: float(columns[m][-1]) for m in self.metrics}}


def smoothed(values: np.ndarray, window: int) -> np.ndarray:
    """The mean of the last ``window`` values (fewer at the start) at each position."""
    sums = np.cumsum(np.concatenate([[0.0], values]))
    counts = np.minimum(np.arange(1, len(values) + 1), window)
    ends = np.arange(1, len(values) + 1)
    return (sums[ends] - sums[ends - counts]) / counts


def learning_curves(folder: Path, window: int = WINDOW) -> list[RunCurves]:
    """The runs of a models folder, each with its seeds' smoothed curves (seeds whose monitor
    file has no finished episode yet are left out). A monitor file is read as untrusted data
    (`baselines.rl.monitor.read_monitor`): a link at its name, or a value out of its bounds, is
    a `ConfigError`."""
    if window < 1:
        raise ConfigError(f"window: expected an integer >= 1, got {window}")
    if not folder.is_dir():
        raise ConfigError(f"curves: {str(folder)!r} is not a folder")
    runs: dict[str, RunCurves] = {}
    for path in sorted(folder.iterdir()):
        match = _MONITOR.fullmatch(path.name)
        # not a pipe or a folder of that name; a link is read_monitor's to refuse
        if not match or not (path.is_symlink() or path.is_file()):
            continue
        columns = read_monitor(path)
        if not len(columns["l"]):
            continue
        curves = {"steps": columns["steps"], "episodes": np.asarray(len(columns["l"]))}
        for key, metric in METRICS.items():
            if key in columns:
                curves[metric] = smoothed(columns[key], window)
        run = runs.setdefault(match.group("run"), RunCurves(match.group("run")))
        run.seeds[int(match.group("seed"))] = curves
    for run in runs.values():
        run.seeds = dict(sorted(run.seeds.items()))
    return list(runs.values())
