"""The paired benchmark of the tests' Snakemake server (``benchmarks/server_preload.py``): the ratio
is taken round by round, and each round's two measurements stay together."""

from __future__ import annotations

from helpers import benchmark

server_preload = benchmark("server_preload")


def test_the_ratio_is_taken_round_by_round():
    rounds = [
        {"cli_only": {"wall_s": 2.0, "load1_before": 0.5}, "preloaded": {"wall_s": 1.5, "load1_before": 0.6}},
        {"cli_only": {"wall_s": 4.0, "load1_before": 1.5}, "preloaded": {"wall_s": 2.0, "load1_before": 1.4}},
        {"cli_only": {"wall_s": 2.2, "load1_before": 0.7}, "preloaded": {"wall_s": 2.2, "load1_before": 0.7}},
    ]
    out = server_preload.compare(rounds)
    # per round 0.75, 0.5, 1.0: not the ratio of the medians (1.5 / 2.2)
    ratio = out["preloaded_over_cli_only"]
    assert (ratio["median"], ratio["min"], ratio["max"]) == (0.75, 0.5, 1.0)
    assert ratio["interval"]["value"] == 0.75 and ratio["verdict"] == "tie"  # resamples of 0.5 ... 1.0
    assert out["wall_s_per_call"]["cli_only"] == {"median": 2.2, "min": 2.0, "max": 4.0}
    assert out["load1_before"]["max"] == 1.5
    faster = [
        {"cli_only": {"wall_s": 2.0 + k / 100, "load1_before": 0.5}, "preloaded": {"wall_s": 1.6, "load1_before": 0.5}}
        for k in range(8)
    ]
    assert server_preload.compare(faster)["preloaded_over_cli_only"]["verdict"] == "below"
