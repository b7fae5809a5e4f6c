"""Solver configurations raced on one system (``benchmarks/race.py``): round-robin under the timing
protocol, certified alike, compared with the reference configuration; a configuration started from
the cascade is charged with its start, as the study's measurement charges it."""

from __future__ import annotations

import math

from helpers import benchmark

from signorini.studies.work_precision.study import study_configs
from signorini.timing import Protocol, Timer

FAST = {"wait_s": 0.0, "retries": 0, "min_repeats": 1, "budget_s": 1.0}  # no waiting for a quiet machine


race = benchmark("race")


def test_exact_routes_agree_with_the_reference_and_a_failing_one_stops_its_task_only(cache):
    disc = cache.discrete({}, 21)
    configs = study_configs({"configs": {
        "active_set": {"solver": "active_set", "label": "direct"},
        "cold": {"solver": "active_set", "label": "direct (cold)", "options": {"warm_start": None}},
        "multigrid": {"solver": "multigrid", "label": "multigrid", "options": {"max_coarse": 20}},
        "truncated": {"solver": "active_set", "label": "one step", "options": {"warm_start": None, "max_iter": 1}},
    }})
    out = race.race(disc, configs, None, Timer(Protocol.from_mapping(FAST)))
    runs = out["configs"]
    assert race.REFERENCE == "active_set" and list(runs) == ["active_set", "cold", "multigrid", "truncated"]
    for name in ("active_set", "cold", "multigrid"):
        assert runs[name]["status"] == "ok" and runs[name]["agreement"] <= 1e-12, (name, runs[name])
        assert runs[name]["time_s"] > 0 and runs[name]["iterations"] >= 1
    assert runs["active_set"]["agreement"] == 0.0 and runs["active_set"]["ratio_cpu"] == 1.0
    interval = runs["cold"]["ratio_cpu_interval"]  # the ratio with its bootstrap interval and verdict
    assert interval["value"] == runs["cold"]["ratio_cpu"] and interval["verdict"] in ("tie", "below", "above",
                                                                                      "undetermined")
    assert not interval["interval"] or interval["lo"] <= interval["value"] <= interval["hi"]
    assert runs["cold"]["start"] == "cold" and runs["active_set"]["start"] == "cascade"
    assert runs["truncated"]["status"] == "failed" and math.isnan(runs["truncated"]["agreement"])
    assert out["start"] == {}  # no peer started from the cascade: no coarse solve timed for one


def test_a_qp_solver_is_judged_against_its_tolerance(cache):
    disc = cache.discrete({}, 11)
    configs = study_configs({"configs": {"active_set": {"solver": "active_set"}}, "qp_solvers": ["cvxpy_osqp"]})
    runs = race.race(disc, configs, 1e-6, Timer(Protocol.from_mapping(FAST)))["configs"]
    assert runs["osqp"]["status"] in ("ok", "inaccurate") and runs["osqp"]["agreement"] < 1e-3
    assert runs["osqp"]["label"] == "OSQP" and runs["osqp"]["ratio_cpu"] > 0
