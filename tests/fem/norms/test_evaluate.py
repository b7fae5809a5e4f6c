"""The one entry point for named norms of both kinds (``signorini.fem.norms.evaluate``): the order
asked for, each value the one its evaluator gives, each name parsed once."""

from __future__ import annotations

import numpy as np
import pytest

from signorini.fem.discrete import build
from signorini.fem.norms import names as norm_names
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.evaluate import evaluate_named_norms
from signorini.fem.norms.names import UnknownNormError, parse_norm_name
from signorini.fem.norms.true import true_norm
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete

NAMES = ["L4_true", "L4", "W1inf", "H12_true", "Linfplus", "H12", "W14_true"]


@pytest.fixture(scope="module")
def solution():
    disc = build(Problem(), 9)
    return disc.problem, disc.mesh, solve_discrete(disc).u


def test_each_name_is_evaluated_by_its_evaluator_in_the_order_asked_for(solution):
    problem, mesh, u_h = solution
    conv = Conventions(w1p_form="gradient", h12_form="geometric_semi")
    out = evaluate_named_norms(problem, mesh, u_h, NAMES, conv)
    assert list(out) == NAMES
    plain = evaluate_norms(problem, mesh, u_h, [n for n in NAMES if not n.endswith("_true")], conv)
    for name in NAMES:
        expected = true_norm(problem, mesh, u_h, name, conv).value if name.endswith("_true") else plain[name]
        assert np.float64(out[name]).tobytes() == np.float64(expected).tobytes(), name
    detailed = evaluate_named_norms(problem, mesh, u_h, NAMES, conv, details=True)
    assert detailed["W14_true"].as_dict() == true_norm(problem, mesh, u_h, "W14_true", conv).as_dict()
    assert detailed["L4"] == out["L4"] and detailed["H12_true"].value == out["H12_true"]


def test_each_name_is_parsed_once_and_parsed_names_are_taken_as_they_are(solution, monkeypatch):
    problem, mesh, u_h = solution
    expected = evaluate_named_norms(problem, mesh, u_h, NAMES)
    calls = []
    parse = norm_names.parse_norm_name
    monkeypatch.setattr(norm_names, "parse_norm_name", lambda name: calls.append(name) or parse(name))
    assert evaluate_named_norms(problem, mesh, u_h, NAMES) == expected
    assert sorted(calls) == sorted(NAMES)  # once each, however many layers a name passes
    calls.clear()
    assert evaluate_named_norms(problem, mesh, u_h, [parse(n) for n in NAMES]) == expected
    assert calls == []


def test_unknown_names_fail_before_any_work(solution, monkeypatch):
    import signorini.fem.norms.evaluate as evaluate

    problem, mesh, u_h = solution
    monkeypatch.setattr(evaluate, "true_norm", lambda *args: pytest.fail("evaluated"))
    monkeypatch.setattr(evaluate, "evaluate_norms", lambda *args: pytest.fail("evaluated"))
    for names in (["L4_true", "nonsense"], ["L4", "W14plus"]):
        with pytest.raises(UnknownNormError):
            evaluate_named_norms(problem, mesh, u_h, names)
    assert parse_norm_name("L4_true").true
