"""The count of the frontier's first reach (``benchmarks/frontier_first_reach.py``): both reaches
on one mesh and route, their counts and the agreement of their answers."""

from __future__ import annotations

from helpers import benchmark

frontier_first_reach = benchmark("frontier_first_reach")


def test_both_reaches_are_counted_and_agree():
    out = frontier_first_reach.run({}, 101)
    assert set(out) == {"multigrid", "active_set"}
    for route, runs in out.items():
        one, two = runs["reach1"], runs["reach2"]
        assert two["newton_steps"] < one["newton_steps"], route
        assert runs["same_contact_set"] and runs["max_difference_over_max_u"] <= 1e-12
    assert out["multigrid"]["reach2"]["v_cycles"] < out["multigrid"]["reach1"]["v_cycles"]
    assert out["active_set"]["reach1"]["v_cycles"] is None
