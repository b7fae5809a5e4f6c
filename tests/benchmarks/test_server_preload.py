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
    assert out["preloaded_over_cli_only"] == {"median": 0.75, "min": 0.5, "max": 1.0}
    assert out["wall_s_per_call"]["cli_only"] == {"median": 2.2, "min": 2.0, "max": 4.0}
    assert out["load1_before"]["max"] == 1.5
    # the medians 2.0 and 2.2 with their bootstrap: an interval that holds 1 here, a tie
    assert out["ratio_of_medians"]["value"] == 2.0 / 2.2 and out["ratio_of_medians"]["verdict"] == "tie"
