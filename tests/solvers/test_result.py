"""The result of every solver route (``signorini.solvers.result.SolveResult``): its JSON-ready
summary."""

from __future__ import annotations

import json

import numpy as np

from signorini.solvers.certificate import Certificate
from signorini.solvers.result import SolveResult


def test_the_summary_is_json_ready_and_holds_everything_but_the_vectors():
    history = [{"iteration": 1, "active": 3, "changes": 3}, {"iteration": 2, "active": 4, "changes": 1}]
    result = SolveResult(
        u=np.zeros(9),
        lam=np.ones(8),
        active=np.array([0, 1, 2, 5]),
        iterations=np.int64(2),
        wall_time_s=np.float64(0.25),
        certificate=Certificate(1e-14, 0.0, 0.0, 1e-15, 1e-10),
        solver="active_set",
        info={"factorizations": 1, "backend": "superlu"},
        history=history,
    )
    summary = result.summary()
    assert json.loads(json.dumps(summary)) == summary
    assert type(summary["iterations"]) is int and type(summary["wall_time_s"]) is float
    assert summary["n_active"] == 4 and summary["factorizations"] == 1 and summary["backend"] == "superlu"
    assert summary["certificate"]["ok"] and summary["certificate"]["worst"] == 1e-14
    assert not {"u", "lam", "active"} & set(summary)
    summary["history"][0]["changes"] = 99  # a copy: the result's history is untouched
    assert result.history[0]["changes"] == 3


def test_the_summary_of_a_solve_matches_its_result(cache):
    result = cache.solution({}, 11)
    summary = result.summary()
    assert summary["solver"] == "active_set" and summary["n_active"] == result.active.size
    assert summary["iterations"] == result.iterations == len(summary["history"])
    assert summary["certificate"] == result.certificate.as_dict()
