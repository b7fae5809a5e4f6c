"""Exact norms of a P1 function (``signorini.fem.norms.p1``) against closed forms.

They are compared with the quadrature norms of ``fem.norms.conventional`` in
``tests/studies/work_precision/test_measure.py``.
"""

from __future__ import annotations

import math

import pytest

from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.p1 import p1_norms


def test_norms_of_x1_are_the_closed_forms_and_scale_with_the_function():
    """v = x₁ is P1 on every mesh: ‖v‖_{L^p} = (1/(p+1))^{1/p} (even p exactly, odd p by the
    conical rule, exact for |x₁|³ = x₁³), |∇v| = 1, max |v| = 1, ∮ v² = 5/3, ∮ (∂_t v)² = 2."""
    mesh = friedrichs_keller(5, "nw_se")
    names = ["L2", "L3", "L4", "L16", "Linf", "W14", "W1inf", "H1", "L2boundary", "H12"]
    conv = Conventions(w1p_form="gradient", h12_form="geometric_full")
    norms = p1_norms(mesh, mesh.p[0], names, conv)
    l2b, semi = math.sqrt(5 / 3), math.sqrt(2.0)
    expected = {
        **{f"L{p}": (1.0 / (p + 1)) ** (1.0 / p) for p in (2, 3, 4, 16)},
        "Linf": 1.0,
        "W14": (1.0 / 5 + 1.0) ** 0.25,
        "W1inf": 1.0,
        "H1": math.sqrt(1 / 3 + 1),
        "L2boundary": l2b,
        "H12": math.sqrt(l2b * math.hypot(l2b, semi)),
    }
    for name in names:
        assert norms[name] == pytest.approx(expected[name], rel=1e-13), name
    scaled = p1_norms(mesh, -1e-200 * mesh.p[0], names, conv)  # homogeneous, no underflow
    for name in names:
        assert scaled[name] == pytest.approx(1e-200 * norms[name], rel=1e-13), name
