"""Interval estimates for evaluation tables: one uncertainty model for every cell of a table
(`row_estimate`), verdicts by probability of improvement (`improvement`), and the estimators
they grew from (Wilson intervals, bootstrap means, the IQM and performance profiles over runs).

**The protocol of the tables** (Agarwal et al., "Deep RL at the edge of the statistical
precipice", NeurIPS 2021, the methods of the ``rliable`` package, extended from runs to the
episodes inside them):

* A row of a table is a list of **runs**, each a list of per-episode values: a trained
  algorithm has one run per training seed; a planner or a baseline is one run.
* Its **point estimate** is the interquartile mean (IQM, 25% trimmed from each end) of the runs'
  means; with fewer than four runs nothing is trimmed, and one run's estimate is its mean.
* Its **95% interval** is a percentile bootstrap over both levels: each resample draws the runs
  with replacement and then, inside every drawn run, its episodes with replacement, and
  recomputes the IQM (`row_estimate`). Episode noise is therefore in every interval, also with
  few runs, and a planner's interval is the same bootstrap with one run. A rate whose episodes
  all agree (0 or n successes) has a point interval; the count beside it says how much that is
  worth.
* A **verdict** between two rows uses the probability of improvement P(X > Y): the chance that
  an episode of X (a random run, then a random episode of it) scores better than an episode of
  Y, ties counting one half — the Mann–Whitney statistic U / (n·m) with the runs weighted
  equally. Its interval is the same two-level bootstrap, X and Y resampled independently. X
  wins only when the interval's lower bound is above 0.5 (`improvement`).

* A **rate** (a yes/no outcome per episode, e.g. success) gets the Wilson score interval
  (Wilson 1927), through `scipy.stats.binomtest`; unlike the normal approximation it stays
  inside [0, 1] and is not empty at 0 or n successes.
* A **mean** gets a bootstrap interval: `scipy.stats.bootstrap`, bias-corrected and accelerated
  (BCa), 9,999 resamples, from a fixed seed, so the same values give the same interval. Where
  BCa is undefined (its acceleration is 0/0 for some small or lopsided samples) the percentile
  interval is used instead. A **band** (a curve per episode, e.g. coverage against steps) is
  that interval at every point of the curve (`mean_band`).
* Across **training seeds** (Agarwal et al., "Deep RL at the edge of the statistical precipice",
  NeurIPS 2021): the IQM — the mean of the middle 50% of the per-run scores (25% trimmed from
  each end, `scipy.stats.trim_mean`) — with a *stratified* percentile bootstrap: every task's runs
  are resampled separately. `scipy.stats.bootstrap` given one sample per task does exactly that
  (it resamples each sample independently). The performance profile is, per threshold τ, the
  fraction of runs scoring above τ (averaged over tasks), with the same bootstrap.

The run-level estimators are the `rliable` package's (checked against its values in the tests);
they are computed with numpy and scipy because rliable 1.2.0 pulls in arch, statsmodels, pandas and
seaborn, fails to import with pandas 3 (arch's decorators), and seeds its bootstrap only through
numpy's legacy global state; it also resamples runs only, not the episodes within them.

Every interval is ``None`` where there is nothing to resample (fewer than two values).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

#: Confidence level of every interval.
CONFIDENCE = 0.95
#: Bootstrap resamples.
N_RESAMPLES = 9999
#: Seed of every bootstrap: the same values give the same interval.
SEED = 0
#: Fraction trimmed from each end for the interquartile mean.
IQM_TRIM = 0.25


@dataclass(frozen=True)
class Estimate:
    """A point estimate, its 95% interval (``None`` if there is none) and the count it rests on."""

    value: float
    lo: float | None
    hi: float | None
    n: int

    def store(self, entry: dict, key: str) -> None:
        """Write it into a summary row as ``key``, ``key_lo``, ``key_hi`` and ``key_n``."""
        entry.update({key: self.value, f"{key}_lo": self.lo, f"{key}_hi": self.hi,
                      f"{key}_n": self.n})


def wilson_interval(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The Wilson score interval of ``successes`` out of ``n`` (n >= 1)."""
    ci = stats.binomtest(int(successes), int(n)).proportion_ci(confidence_level=confidence,
                                                               method="wilson")
    return float(ci.low), float(ci.high)


def rate(outcomes: Sequence[bool]) -> Estimate:
    """The fraction of true outcomes with its Wilson interval."""
    n = len(outcomes)
    if n == 0:
        raise ValueError("rate of no outcomes")
    k = int(np.count_nonzero(outcomes))
    lo, hi = wilson_interval(k, n)
    return Estimate(k / n, lo, hi, n)


def bootstrap_mean_interval(values: Sequence[float], confidence: float = CONFIDENCE,
                            n_resamples: int = N_RESAMPLES, seed: int = SEED
                            ) -> tuple[float, float] | None:
    """The BCa bootstrap interval of the mean of ``values`` (``None`` for fewer than two values;
    a point interval when they are all equal, where BCa is undefined)."""
    x = np.asarray(values, dtype=float)
    if x.size < 2:
        return None
    if np.ptp(x) == 0:
        return float(x[0]), float(x[0])
    for method in ("BCa", "percentile"):
        with warnings.catch_warnings():  # BCa's own warning when it is undefined: fall back
            warnings.simplefilter("ignore", stats.DegenerateDataWarning)
            warnings.simplefilter("ignore", RuntimeWarning)
            ci = stats.bootstrap((x,), np.mean, n_resamples=n_resamples,
                                 confidence_level=confidence, method=method, vectorized=True,
                                 rng=np.random.default_rng(seed)).confidence_interval
        if np.isfinite(ci.low) and np.isfinite(ci.high):
            break
    return float(ci.low), float(ci.high)


def mean(values: Sequence[float]) -> Estimate:
    """The mean of ``values`` with its bootstrap interval."""
    x = np.asarray(values, dtype=float)
    if x.size == 0:
        raise ValueError("mean of no values")
    ci = bootstrap_mean_interval(x)
    return Estimate(float(x.mean()), *(ci or (None, None)), int(x.size))


@dataclass(frozen=True)
class Band:
    """Mean curves with their 95% intervals, point by point, over ``n`` curves."""

    mean: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    n: int


#: Resamples per batch of `mean_band` (bounds its memory: batch x curves x points floats).
BAND_BATCH = 500


def mean_band(curves, confidence: float = CONFIDENCE, n_resamples: int = N_RESAMPLES,
              seed: int = SEED) -> Band:
    """The mean of ``curves`` ((n, points): one curve per row) at every point with the interval
    of `bootstrap_mean_interval` (BCa, percentile where BCa is undefined, a point interval where
    all values are equal): one resampling of the rows, the one `bootstrap_mean_interval` draws,
    serves every point. (With tied values BCa's bias correction may then differ by rounding.)
    With fewer than two curves the band is the mean itself."""
    x = np.asarray(curves, dtype=float)
    if x.ndim != 2 or x.shape[0] == 0:
        raise ValueError(f"curves: expected (n >= 1, points), got shape {x.shape}")
    centre = x.mean(axis=0)
    if x.shape[0] < 2:
        return Band(centre, centre.copy(), centre.copy(), x.shape[0])
    lo, hi = centre.copy(), centre.copy()
    todo = np.flatnonzero(np.ptp(x, axis=0) > 0)
    for method in ("BCa", "percentile"):
        if not len(todo):
            break
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", stats.DegenerateDataWarning)
            warnings.simplefilter("ignore", RuntimeWarning)
            ci = stats.bootstrap((x[:, todo],), np.mean, n_resamples=n_resamples,
                                 confidence_level=confidence, method=method, vectorized=True,
                                 axis=0, batch=BAND_BATCH,
                                 rng=np.random.default_rng(seed)).confidence_interval
        low, high = np.atleast_1d(ci.low), np.atleast_1d(ci.high)
        ok = np.isfinite(low) & np.isfinite(high)
        lo[todo[ok]], hi[todo[ok]] = low[ok], high[ok]
        todo = todo[~ok]
    return Band(centre, lo, hi, x.shape[0])


def _tasks(scores) -> list[np.ndarray]:
    """Per-task score arrays from a (runs, tasks) array, a flat sequence of numbers (one task)
    or a list of per-task run scores."""
    flat = isinstance(scores, list | tuple) and all(np.ndim(s) == 0 for s in scores)
    if flat or isinstance(scores, np.ndarray) or not isinstance(scores, list | tuple):
        array = np.asarray(scores, dtype=float)
        array = array[:, None] if array.ndim == 1 else array
        if array.ndim != 2:
            raise ValueError(f"scores: expected (runs, tasks), got shape {array.shape}")
        return [array[:, j] for j in range(array.shape[1])]
    return [np.asarray(task, dtype=float).ravel() for task in scores]


def iqm(scores) -> float:
    """The interquartile mean of all runs of all tasks: ``scipy.stats.trim_mean(·, 0.25)``."""
    return float(stats.trim_mean(np.concatenate(_tasks(scores)), IQM_TRIM))


def _stratified(tasks: list[np.ndarray], statistic, seed: int, n_resamples: int,
                confidence: float):
    return stats.bootstrap(tasks, statistic, n_resamples=n_resamples,
                           confidence_level=confidence, method="percentile", vectorized=True,
                           rng=np.random.default_rng(seed)).confidence_interval


def iqm_estimate(scores, confidence: float = CONFIDENCE, n_resamples: int = N_RESAMPLES,
                 seed: int = SEED) -> Estimate:
    """The IQM of the runs' scores with its stratified-bootstrap percentile interval.

    ``scores``: a (runs, tasks) array (a 1-D array is one task) or a list of per-task run scores
    (tasks may have different numbers of runs). ``n`` is the number of runs of all tasks.
    """
    tasks = _tasks(scores)
    n = sum(t.size for t in tasks)
    value = iqm(tasks)
    if all(t.size < 2 for t in tasks):
        return Estimate(value, None, None, n)

    def statistic(*samples, axis=-1):
        return stats.trim_mean(np.concatenate(samples, axis=axis), IQM_TRIM, axis=axis)

    ci = _stratified(tasks, statistic, seed, n_resamples, confidence)
    return Estimate(value, float(ci.low), float(ci.high), n)


@dataclass(frozen=True)
class Profile:
    """A performance profile: per threshold, the fraction of runs above it, with its interval."""

    taus: np.ndarray
    fraction: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    n: int


def performance_profile(scores, taus: Sequence[float], confidence: float = CONFIDENCE,
                        n_resamples: int = N_RESAMPLES, seed: int = SEED) -> Profile:
    """The score distribution of the runs: for each τ of ``taus`` the fraction of runs scoring
    above τ (per task, then averaged over tasks), with a stratified-bootstrap percentile band
    (the band is the point value itself when no task has two runs)."""
    tasks = _tasks(scores)
    thresholds = np.asarray(taus, dtype=float)

    def statistic(*samples, axis=-1):
        above = [np.mean(np.expand_dims(s, -2) > thresholds[:, None], axis=-1)
                 for s in (np.moveaxis(x, axis, -1) for x in samples)]
        return np.moveaxis(np.mean(above, axis=0), -1, 0)

    fraction = statistic(*tasks)
    if all(t.size < 2 for t in tasks):
        lo = hi = fraction
    else:
        ci = _stratified(tasks, statistic, seed, n_resamples, confidence)
        lo, hi = np.asarray(ci.low, dtype=float), np.asarray(ci.high, dtype=float)
    return Profile(thresholds, fraction, lo, hi, sum(t.size for t in tasks))


#: Fewest training seeds a learner's row needs for a verdict (Agarwal et al. 2021 report that
#: fewer runs make even bootstrap intervals unreliable); rows with fewer are marked in tables.
MIN_SEEDS = 5
#: Decimals a probability of improvement is rounded to (float error of its weights is ~1e-15).
PROBABILITY_DIGITS = 12
#: Slots (resample × run) drawn at once by the two-level bootstrap (bounds its memory).
SLOT_BATCH = 20_000


def _runs(runs) -> list[np.ndarray]:
    """Non-empty per-run value arrays (runs without values left out)."""
    out = [np.asarray(r, dtype=float).ravel() for r in runs]
    out = [r for r in out if r.size]
    if not out:
        raise ValueError("no values in any run")
    return out


def _resampled_runs(runs: list[np.ndarray], rng: np.random.Generator, n_resamples: int,
                    support: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """The two-level bootstrap of the module docstring, ``n_resamples`` times: per resample,
    every drawn run's resampled mean, (resamples, runs), and, given ``support`` (the sorted
    distinct values), the resampled distribution of an episode over it with every drawn run
    weighted equally, (resamples, len(support))."""
    k = len(runs)
    picks = rng.integers(k, size=(n_resamples, k))
    means = np.empty((n_resamples, k))
    weights = None if support is None else np.zeros((n_resamples, support.size))
    for j, run in enumerate(runs):
        slots = np.argwhere(picks == j)  # (resample, position) pairs that drew run j
        codes = None if support is None else np.searchsorted(support, run)
        step = max(SLOT_BATCH // run.size, 1)
        for start in range(0, len(slots), step):
            chunk = slots[start:start + step]
            draw = rng.integers(run.size, size=(len(chunk), run.size))
            means[chunk[:, 0], chunk[:, 1]] = run[draw].mean(axis=1)
            if weights is not None:
                flat = np.arange(len(chunk))[:, None] * support.size + codes[draw]
                counts = np.bincount(flat.ravel(), minlength=len(chunk) * support.size)
                np.add.at(weights, chunk[:, 0],
                          counts.reshape(len(chunk), support.size) / (run.size * k))
    return means, weights


def _iqm_rows(means: np.ndarray) -> np.ndarray:
    return stats.trim_mean(means, IQM_TRIM, axis=-1)


def row_estimate(runs, confidence: float = CONFIDENCE, n_resamples: int = N_RESAMPLES,
                 seed: int = SEED) -> Estimate:
    """A table cell (module docstring): the IQM of the runs' means with its two-level bootstrap
    percentile interval; ``n`` counts the episodes of all runs. ``runs``: a list of per-episode
    value sequences, one per run (runs without values are left out)."""
    runs = _runs(runs)
    value = float(_iqm_rows(np.array([[r.mean() for r in runs]]))[0])
    n = sum(r.size for r in runs)
    if n < 2:
        return Estimate(value, None, None, n)
    if np.ptp(np.concatenate(runs)) == 0:
        return Estimate(value, value, value, n)
    means, _ = _resampled_runs(runs, np.random.default_rng(seed), n_resamples)
    tail = 100 * (1 - confidence) / 2
    lo, hi = np.percentile(_iqm_rows(means), [tail, 100 - tail])
    return Estimate(value, float(lo), float(hi), n)


def _improvement(wx: np.ndarray, wy: np.ndarray) -> np.ndarray:
    """P(X > Y) + P(X = Y) / 2 for distributions ``wx``, ``wy`` over the same sorted support
    (last axis)."""
    below = np.cumsum(wy, axis=-1) - wy  # P(Y < v) at each support value v
    return np.sum(wx * (below + 0.5 * wy), axis=-1)


def improvement(x_runs, y_runs, higher_is_better: bool = True,
                confidence: float = CONFIDENCE, n_resamples: int = N_RESAMPLES,
                seed: int = SEED) -> Estimate:
    """The probability of improvement of X over Y (module docstring) with its two-level
    bootstrap percentile interval; ``n`` counts the episodes of both. With
    ``higher_is_better=False`` an improvement is a lower value. X wins when ``lo > 0.5``, Y when
    ``hi < 0.5`` (`verdict`)."""
    xs, ys = _runs(x_runs), _runs(y_runs)
    if not higher_is_better:
        xs, ys = [-r for r in xs], [-r for r in ys]
    support = np.unique(np.concatenate(xs + ys))

    def distribution(runs):
        w = np.zeros(support.size)
        for r in runs:
            np.add.at(w, np.searchsorted(support, r), 1.0 / (r.size * len(runs)))
        return w

    value = _improvement(distribution(xs), distribution(ys))
    n = sum(r.size for r in xs + ys)
    rng = np.random.default_rng(seed)
    _, wx = _resampled_runs(xs, rng, n_resamples, support)
    _, wy = _resampled_runs(ys, rng, n_resamples, support)
    tail = 100 * (1 - confidence) / 2
    lo, hi = np.percentile(_improvement(wx, wy), [tail, 100 - tail])
    # the weights are sums of 1/(episodes x runs): round off their float error, so that ties
    # read exactly 0.5 and never count as a win
    value, lo, hi = (round(float(v), PROBABILITY_DIGITS) for v in (value, lo, hi))
    return Estimate(value, lo, hi, n)


def verdict(p: Estimate) -> int:
    """+1 when X improves on Y (the interval of P(X > Y) lies above 0.5), -1 when Y improves on
    X (below 0.5), 0 when undecided."""
    if p.lo is not None and p.lo > 0.5:
        return 1
    if p.hi is not None and p.hi < 0.5:
        return -1
    return 0
