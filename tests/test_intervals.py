"""Intervals of times, ratios and exponents (``signorini.intervals``): a seeded bootstrap over each
measurement's samples, as the work-precision study's runs (``Run.time_estimate``) and the benchmarks use it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from signorini import intervals as unc
from signorini.studies.work_precision.table import Run


def _run(times: str, time_s: float, N: int = 101, config: str = "a") -> Run:
    return Run(N, 1 / (N + 1), (N + 1) ** 2, config, "OSQP", config, tol_label="1e-08", times=times, time_s=time_s)


def _time(run: Run) -> unc.Estimate:
    return run.time_estimate()


def test_a_median_without_a_given_value_is_the_samples_median():
    t = unc.median(np.array([3.0, 1.0, 2.0]), ("key",))
    assert t.value == 2.0 and t.interval == (1.0, 3.0)
    assert unc.median(np.array([3.0, 1.0, 2.0]), ("key",)).interval == t.interval  # seeded by the key


def test_samples_are_parsed_from_the_times_cell():
    np.testing.assert_array_equal(unc.samples("0.1 0.2 0.3"), [0.1, 0.2, 0.3])
    assert unc.samples("").size == 0  # a run without samples (a missing cell is read as "")


def test_a_runs_interval_lies_within_its_samples_shifted_by_what_its_time_adds():
    """The bootstrap of a median stays within the samples' range; a cascade start's cost (the time
    over the samples' median) shifts it; the same run gives the same interval every time."""
    t = _time(_run("1.0 1.1 1.2 1.3 1.4", 1.2))
    lo, hi = t.interval
    assert 1.0 <= lo <= 1.2 <= hi <= 1.4 and t.value == 1.2
    started = _time(_run("1.0 1.1 1.2 1.3 1.4", 1.7))  # + 0.5 s of start
    assert started.interval == pytest.approx((lo + 0.5, hi + 0.5))
    assert _time(_run("1.0 1.1 1.2 1.3 1.4", 1.2)).interval == (lo, hi)
    other = _time(_run("1.0 1.1 1.2 1.3 1.4", 1.2, N=201))  # another run: its own resamples
    assert not np.array_equal(other.boot, t.boot)
    # three samples: their median's bootstrap reaches from the smallest to the largest
    assert _time(_run("1.0 1.5 2.0", 1.5)).interval == (1.0, 2.0)


def test_a_single_sample_has_no_interval():
    t = _time(_run("3.0", 3.0))
    assert t.interval is None and t.summary() == {"value": 3.0, "lo": math.nan, "hi": math.nan, "interval": False}
    assert unc.verdict(unc.ratio(t, _time(_run("6.0", 6.0)))) == "undetermined"
    with_other = unc.ratio(_time(_run("5.0 6.0 7.0", 6.0)), t)
    assert with_other.interval == pytest.approx((5.0 / 3.0, 7.0 / 3.0))  # the other run's spread only


def test_a_ratio_whose_interval_contains_1_is_a_tie():
    ours = _time(_run("1.0 1.1 1.2", 1.1, config="ours"))
    close = _time(_run("1.05 1.15 1.25", 1.15, config="other"))
    far = _time(_run("2.0 2.1 2.2", 2.1, config="other"))
    assert unc.verdict(unc.ratio(close, ours)) == "tie"
    assert unc.verdict(unc.ratio(far, ours)) == "above" and unc.verdict(unc.ratio(ours, far)) == "below"
    r = unc.ratio(far, ours)
    assert r.value == pytest.approx(2.1 / 1.1) and r.interval[0] >= 2.0 / 1.2 - 1e-12


def test_an_exponent_is_refitted_through_the_resamples():
    n = [1e4, 4e4, 9e4, 16e4]
    exact = [_time(_run(f"{1e-6 * x**1.5:.6g}", 1e-6 * x**1.5, N=k)) for k, x in enumerate(n)]
    p = unc.exponent(n, exact)
    assert p.value == pytest.approx(1.5, rel=1e-5) and p.interval is None  # single samples: no interval
    noisy = [
        _time(_run(" ".join(f"{1e-6 * x**1.5 * f:.6g}" for f in (0.9, 1.0, 1.1)), 1e-6 * x**1.5, N=k))
        for k, x in enumerate(n)
    ]
    q = unc.exponent(n, noisy)
    assert q.value == pytest.approx(1.5, rel=1e-5) and q.interval[0] < 1.5 < q.interval[1]
    # error against time: the time is the resampled side
    slope = unc.exponent([unc.shifted(t, 0.0) for t in noisy], [x**-0.75 for x in n])
    assert slope.value == pytest.approx(-0.5, rel=1e-5) and slope.interval[0] < -0.5 < slope.interval[1]
    assert math.isnan(unc.exponent([1.0], [2.0]).value)
