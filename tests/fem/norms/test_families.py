"""The definitions of the norm families (``signorini.fem.norms.families``): what each norm combines
under each convention, the parts as functions of ``(e, ∇e)``, and a family that the three
evaluators take from its definition alone."""

from __future__ import annotations

import math

import numpy as np
import pytest

from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms import families
from signorini.fem.norms import names as norm_names
from signorini.fem.norms.conventions import H12_FORMS, W1P_FORMS, Conventions
from signorini.fem.norms.families import (
    BOUNDARY,
    MAX,
    P_SUM,
    SQUARES,
    NormDefinition,
    define,
    magnitude,
    part,
)
from signorini.fem.norms.names import parse_norm_name
from signorini.fem.problem import ProblemBase


@pytest.mark.parametrize("form", W1P_FORMS)
@pytest.mark.parametrize("h12_form", H12_FORMS)
def test_each_family_combines_its_parts(form, h12_form):
    conv = Conventions(w1p_form=form, h12_form=h12_form)
    w1p = {"components": ("e", "d1", "d2"), "gradient": ("e", "grad"), "seminorm": ("grad",)}[form]
    expected = {
        "L4": (P_SUM, ("e",), "", ()),
        "L2.5plus": (P_SUM, ("e+",), "", ()),
        "Linfminus": (MAX, ("e-",), "linf_points", ()),
        "Linf": (MAX, ("e",), "linf_points", ()),
        "W116": (P_SUM, w1p, "", ()),
        "W1inf": (MAX, w1p, "w1inf_points", ()),
        "H1": (SQUARES, ("e", "d1", "d2"), "", ()),
        "L2boundary": (BOUNDARY, (), "", (("e",),)),
        "H12": (BOUNDARY, (), "", (("e",), ("e", "dt") if h12_form == "geometric_full" else ("dt",))),
    }
    for name, (combination, parts, points, factors) in expected.items():
        norm = define(name, conv)
        assert (norm.combination, norm.parts, norm.points, norm.factors) == (combination, parts, points, factors)
        true = define(name + "_true", conv)  # the converged evaluation of the same norm
        assert (true.combination, true.parts, true.factors) == (combination, parts, factors)
        assert norm.name == parse_norm_name(name) and true.name.true


def test_the_properties_of_a_definition():
    assert define("H1").p == 2.0 and define("W12.5").p == 2.5 and math.isinf(define("W1inf").p)
    assert define("H12").p is None and define("H12").boundary_parts == ("e", "dt")
    assert define("H12", Conventions(h12_form="geometric_semi")).boundary_parts == ("e", "dt")
    assert define("L2boundary").boundary_parts == ("e",)
    assert define("L4plus").one_sided and not define("L4").one_sided
    assert not define("L16").needs_gradient and define("H1").needs_gradient
    assert define("W14", Conventions(w1p_form="seminorm")).needs_gradient
    assert define(parse_norm_name("W14")) == define("W14")  # a parsed name as it is
    assert set(families.FAMILIES) == set(norm_names.NAMED_NORMS) | {"L", "W1"}  # every family of the grammar


def test_the_parts_and_their_magnitudes_pointwise():
    e = np.array([-2.0, 0.0, 3.0])
    de = np.array([[3.0, -1.0, 0.0], [-4.0, 0.0, 2.0]])
    expected = {
        "e": (e, [2.0, 0.0, 3.0]),
        "e+": ([0.0, 0.0, 3.0], [0.0, 0.0, 3.0]),
        "e-": ([2.0, 0.0, 0.0], [2.0, 0.0, 0.0]),
        "d1": (de[0], [3.0, 1.0, 0.0]),
        "d2": (de[1], [4.0, 0.0, 2.0]),
        "grad": ([5.0, 1.0, 2.0], [5.0, 1.0, 2.0]),
    }
    assert set(expected) == set(families.PARTS)
    for name, (value, size) in expected.items():
        np.testing.assert_array_equal(part(name, e, de), value)
        np.testing.assert_array_equal(magnitude(name, e, de), size)


class Linear(ProblemBase):
    """u(x) = a1 x₁ + a2 x₂ (no singular point)."""

    def __init__(self, a1: float, a2: float):
        self.a = (a1, a2)

    def u(self, x):
        return self.a[0] * x[0] + self.a[1] * x[1]

    def grad_u(self, x):
        return np.stack([np.full(x.shape[1:], self.a[0]), np.full(x.shape[1:], self.a[1])])


def test_a_family_of_existing_parts_is_one_definition_for_the_three_evaluators(monkeypatch):
    """The H¹ seminorm ``‖∇e‖_{L²}``, given only its name's exponent and its definition (the sum of
    squares of ``∂₁e`` and ``∂₂e``), is evaluated under the conventions, to a stated accuracy and
    exactly for a P1 function: ``|∇e| = √5`` for ``e = 2x₁ − x₂`` on the unit square."""
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.norms.p1 import p1_norms
    from signorini.fem.norms.true import true_norm

    monkeypatch.setitem(norm_names.NAMED_NORMS, "H1semi", 2.0)
    monkeypatch.setitem(families.FAMILIES, "H1semi", lambda spec, conv: NormDefinition(spec, SQUARES, ("d1", "d2")))
    mesh, problem = friedrichs_keller(6), Linear(2.0, -1.0)
    zero = np.zeros(mesh.p.shape[1])
    assert evaluate_norms(problem, mesh, zero, ["H1semi"])["H1semi"] == pytest.approx(math.sqrt(5.0), rel=1e-14)
    assert true_norm(problem, mesh, zero, "H1semi_true").value == pytest.approx(math.sqrt(5.0), rel=1e-14)
    assert p1_norms(mesh, problem.u(mesh.p), ["H1semi"])["H1semi"] == pytest.approx(math.sqrt(5.0), rel=1e-14)
