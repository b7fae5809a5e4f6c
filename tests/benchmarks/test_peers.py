"""The race against the PETSc peers (``benchmarks/peers.py``): each method's CPU time over ours
with its bootstrap interval and verdict, and the target met only when the whole interval lies
above it."""

from __future__ import annotations

import sys

from helpers import ROOT, benchmark

sys.path.insert(0, str(ROOT / "benchmarks"))  # the script imports race.py from next to it
peers = benchmark("peers")


def _rec(times: list[float], status: str = "ok") -> dict:
    return {"time_s": sorted(times)[len(times) // 2], "times": " ".join(map(str, times)), "status": status}


def test_the_fastest_certified_method_and_the_target_follow_the_intervals():
    configs = {
        "ours": _rec([1.0, 1.02, 0.98]),
        "slow": _rec([8.0, 8.2, 7.9]),
        "close": _rec([4.9, 5.3, 5.1]),
        "wrong": _rec([0.5, 0.5, 0.5], status="inaccurate"),  # faster but not certified: not the fastest
    }
    out = peers.comparison(configs, "ours", ["slow", "close", "wrong"], "")
    assert out["ratios"]["slow"]["verdict"] == "above" and out["ratios"]["wrong"]["verdict"] == "below"
    fastest = out["fastest"]
    assert fastest["method"] == "close" and fastest["ratio"]["lo"] < peers.TARGET_RATIO < fastest["ratio"]["hi"]
    assert fastest["met"] is False  # 5× within the interval: not shown to be met
    clear = peers.comparison(configs, "ours", ["slow"], "")
    assert clear["fastest"]["met"] is True and clear["fastest"]["ratio"]["lo"] > peers.TARGET_RATIO
