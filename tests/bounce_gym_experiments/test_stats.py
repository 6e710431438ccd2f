"""bounce_gym_experiments.stats against known values: statsmodels' Wilson intervals, the t interval for a
large sample, and rliable 1.2.0's IQM, stratified-bootstrap intervals and performance profiles
(computed once with rliable, 50,000 resamples, on the arrays below)."""

import numpy as np
import pytest
from scipy import stats as scipy_stats

from bounce_gym_experiments import stats

# statsmodels.stats.proportion.proportion_confint(k, n, method="wilson")
WILSON = [
    (103, 200, 0.44610849192745716, 0.5833261482812249),
    (0, 10, 0.0, 0.27753279986288926),
    (5, 10, 0.23659309051256394, 0.7634069094874361),
    (1, 1, 0.2065493143772374, 1.0),
    (19, 20, 0.7638688065532577, 0.9911185511992044),
    (3, 8, 0.13684428582359737, 0.6942576053973728),
]

# per-seed scores: 5 runs of one task, and 6 runs of two tasks
RUNS = np.array([[0.42], [0.55], [0.61], [0.38], [0.70]])
TWO_TASKS = np.array([[12.0, 0.2], [15.0, 0.5], [9.0, 0.4], [20.0, 0.9], [11.0, 0.3],
                      [14.0, 0.6]])
# rliable: library.get_interval_estimates(..., metrics.aggregate_iqm, reps=50000)
RLIABLE_IQM = [(RUNS, 0.52666667, 0.39333333, 0.67), (TWO_TASKS, 5.66666667, 4.8, 7.23333333)]
# rliable: library.create_performance_profile({"x": RUNS}, TAUS, reps=50000)
TAUS = [0.3, 0.4, 0.5, 0.6, 0.65, 0.75]
RLIABLE_PROFILE = ([1.0, 0.8, 0.6, 0.4, 0.2, 0.0], [1.0, 0.4, 0.2, 0.0, 0.0, 0.0],
                   [1.0, 1.0, 1.0, 0.8, 0.6, 0.0])


@pytest.mark.parametrize(("k", "n", "lo", "hi"), WILSON)
def test_wilson_interval_matches_statsmodels(k, n, lo, hi):
    assert stats.wilson_interval(k, n) == pytest.approx((lo, hi), abs=1e-12)
    estimate = stats.rate([True] * k + [False] * (n - k))
    assert (estimate.value, estimate.lo, estimate.hi, estimate.n) == pytest.approx(
        (k / n, lo, hi, n), abs=1e-12)


def test_a_rate_of_nothing_is_an_error():
    with pytest.raises(ValueError):
        stats.rate([])


def test_bootstrap_mean_interval_agrees_with_the_t_interval_on_a_large_sample():
    x = np.random.default_rng(0).normal(10.0, 2.0, 400)
    t_lo, t_hi = scipy_stats.t.interval(0.95, len(x) - 1, loc=x.mean(),
                                        scale=scipy_stats.sem(x))
    lo, hi = stats.bootstrap_mean_interval(x)
    assert lo == pytest.approx(t_lo, abs=0.03) and hi == pytest.approx(t_hi, abs=0.03)
    assert lo < x.mean() < hi


def test_bootstrap_is_deterministic_and_handles_small_samples():
    x = np.random.default_rng(1).exponential(30.0, 50)
    assert stats.bootstrap_mean_interval(x) == stats.bootstrap_mean_interval(x.copy())
    assert stats.bootstrap_mean_interval(x, seed=1) != stats.bootstrap_mean_interval(x)
    assert stats.bootstrap_mean_interval([7.0]) is None
    assert stats.bootstrap_mean_interval([3.0, 3.0, 3.0]) == (3.0, 3.0)
    one = stats.mean([23.0])
    assert (one.value, one.lo, one.hi, one.n) == (23.0, None, None, 1)
    # values equal up to rounding: BCa is undefined (0/0), the percentile interval is used
    near = [0.5925925925925926, 0.5925925925925926, 0.5925925925925927]
    lo, hi = stats.bootstrap_mean_interval(near)
    assert np.isfinite([lo, hi]).all() and lo <= np.mean(near) <= hi


def test_iqm_is_the_25_percent_trimmed_mean():
    assert stats.iqm(np.arange(1.0, 11.0)) == 5.5  # 3..8
    assert stats.iqm([0.1, 0.4, 0.5, 0.7, 0.9]) == pytest.approx((0.4 + 0.5 + 0.7) / 3)
    assert stats.iqm(RUNS) == pytest.approx(0.52666667, abs=1e-8)


@pytest.mark.parametrize(("scores", "value", "lo", "hi"), RLIABLE_IQM)
def test_iqm_interval_matches_rliable(scores, value, lo, hi):
    estimate = stats.iqm_estimate(scores, n_resamples=50_000)
    assert estimate.value == pytest.approx(value, abs=1e-8)
    assert (estimate.lo, estimate.hi) == pytest.approx((lo, hi), abs=0.02)
    assert estimate.n == scores.size


def test_the_bootstrap_is_stratified_by_task():
    """Five runs scoring 0 on one task and five scoring 1 on another: resampled within each
    task, every resample keeps five of each, so the IQM never moves; pooled resampling would."""
    estimate = stats.iqm_estimate([np.zeros(5), np.ones(5)])
    assert (estimate.value, estimate.lo, estimate.hi, estimate.n) == (0.5, 0.5, 0.5, 10)
    ragged = stats.iqm_estimate([np.array([1.0, 2.0, 3.0]), np.array([10.0, 11.0])])
    assert ragged.n == 5 and ragged.lo < ragged.value < ragged.hi
    assert stats.iqm_estimate([0.4]).lo is None


def test_performance_profile_matches_rliable():
    profile = stats.performance_profile(RUNS, TAUS, n_resamples=50_000)
    fraction, lo, hi = RLIABLE_PROFILE
    assert profile.fraction == pytest.approx(fraction)
    assert profile.lo == pytest.approx(lo, abs=0.02) and profile.hi == pytest.approx(hi, abs=0.02)
    assert profile.n == 5
    single = stats.performance_profile([0.5], [0.4, 0.6])
    assert list(single.fraction) == list(single.lo) == list(single.hi) == [1.0, 0.0]


def test_an_estimate_is_stored_with_its_interval_and_count():
    row = {}
    stats.rate([True, False, True]).store(row, "success")
    assert set(row) == {"success", "success_lo", "success_hi", "success_n"}
    assert row["success_n"] == 3 and row["success_lo"] < row["success"] < row["success_hi"]


def test_a_band_is_the_mean_interval_at_every_point():
    rng = np.random.default_rng(0)
    curves = rng.gamma(2.0, size=(15, 30)).cumsum(axis=1)
    curves[:, 0] = 0.3  # all equal: a point interval
    band = stats.mean_band(curves)
    assert band.n == 15 and np.allclose(band.mean, curves.mean(axis=0))
    assert band.lo[0] == band.hi[0] == pytest.approx(0.3)
    for j in range(1, curves.shape[1]):
        assert (band.lo[j], band.hi[j]) == pytest.approx(
            stats.bootstrap_mean_interval(curves[:, j]))
    one = stats.mean_band(curves[:1])
    assert np.array_equal(one.lo, curves[0]) and np.array_equal(one.hi, curves[0])
    with pytest.raises(ValueError, match="curves"):
        stats.mean_band(np.zeros(3))


def test_probability_of_improvement_of_one_run_is_the_mann_whitney_statistic():
    rng = np.random.default_rng(4)
    x, y = rng.normal(size=50).round(1), (rng.normal(size=70) + 0.3).round(1)  # with ties
    p = stats.improvement([x], [y])
    assert p.value == pytest.approx(scipy_stats.mannwhitneyu(x, y).statistic / (50 * 70))
    assert p.lo < p.value < p.hi and p.n == 120
    lower = stats.improvement([x], [y], higher_is_better=False)
    assert lower.value == pytest.approx(1 - p.value)
    assert stats.improvement([x], [y]) == p  # the same values give the same interval


def test_runs_are_weighted_equally_in_the_probability_of_improvement():
    # run 1 has one episode, run 2 has three: P(X > 0) = (1 + 0) / 2, not 1/4
    p = stats.improvement([[1.0], [-1.0, -1.0, -1.0]], [[0.0]])
    assert p.value == 0.5


def test_a_row_estimate_is_the_iqm_of_run_means_with_episodes_resampled():
    runs = [[1, 0, 1, 1], [0, 0, 1, 0], [1, 1, 1, 1], [0, 1, 0, 1], [1, 0, 0, 0]]
    e = stats.row_estimate(runs)
    means = sorted(np.mean(r) for r in runs)
    assert e.value == pytest.approx(np.mean(means[1:4])) and e.n == 20
    assert 0 <= e.lo < e.value < e.hi <= 1
    assert stats.row_estimate([[3.0, 3.0], [3.0]]) == stats.Estimate(3.0, 3.0, 3.0, 3)
    assert stats.row_estimate([[2.0]]).lo is None
    with pytest.raises(ValueError):
        stats.row_estimate([[], []])
