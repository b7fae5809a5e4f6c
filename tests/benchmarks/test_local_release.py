"""The paired benchmark of settling releases (``benchmarks/local_release.py``): both settings on
one mesh, their counts, the agreement of their answers and the ratio's interval."""

from __future__ import annotations

from helpers import benchmark

local_release = benchmark("local_release")


def test_both_settings_are_counted_and_agree():
    out = local_release.measure(201, 2)
    plain, settled = out["plain"], out["settled"]
    assert plain["local_settles"] == 0 and plain["largest_patch"] == 0
    assert settled["local_settles"] >= 1 and settled["largest_patch"] > 0
    assert settled["v_cycles"] < plain["v_cycles"] and settled["newton_steps"] < plain["newton_steps"]
    assert len(plain["cpu_s"]) == len(settled["cpu_s"]) == 2 and len(settled["steps"]) == settled["newton_steps"]
    assert out["same_contact_set"] and out["max_difference_over_max_u"] <= 1e-12
    assert out["ratio_cpu_interval"]["verdict"] in ("tie", "below", "above", "undetermined")
