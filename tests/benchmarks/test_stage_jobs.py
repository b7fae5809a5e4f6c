"""The paired timing of per-mesh jobs (``benchmarks/stage_jobs.py``): each tree's CPU times, the
median of the pairwise ratios and the ratio of the medians with its bootstrap interval."""

from __future__ import annotations

import pytest
from helpers import benchmark

stage_jobs = benchmark("stage_jobs")


def _runs(baseline: list[float], tree: list[float]) -> dict[str, list[dict]]:
    rec = lambda t: {"cpu_s": t, "peak_rss_gib": 1.0, "load1": [0.1, 0.2]}  # noqa: E731
    return {"baseline": [rec(t) for t in baseline], "tree": [rec(t) for t in tree]}


def test_a_clear_speed_up_is_below_1_and_overlapping_times_are_a_tie():
    faster = stage_jobs.summarise(_runs([10.0, 10.5, 9.8], [6.0, 6.2, 5.9]))
    assert faster["ratio_cpu"] == pytest.approx(6.0 / 10.0, rel=0.05)
    assert faster["ratio_cpu_interval"]["verdict"] == "below"
    assert faster["ratio_cpu_interval"]["hi"] < 1.0 and faster["tree"]["median_cpu_s"] == 6.0
    tied = stage_jobs.summarise(_runs([10.0, 12.0, 9.0], [9.5, 11.0, 10.5]))
    assert tied["ratio_cpu_interval"]["verdict"] == "tie"
    single = stage_jobs.summarise(_runs([10.0], [5.0]))  # one run each: no interval
    assert single["ratio_cpu_interval"]["verdict"] == "undetermined" and single["ratio_cpu"] == 0.5


def test_a_failed_run_is_listed_and_leaves_no_ratio():
    runs = {"baseline": [{"failed": "exit 1", "load1": [0.1]}], "tree": [{"cpu_s": 3.0, "load1": [0.1]}]}
    out = stage_jobs.summarise(runs)
    assert out["baseline"]["failed"] == ["exit 1"] and out["ratio_cpu"] is None and "ratio_cpu_interval" not in out
