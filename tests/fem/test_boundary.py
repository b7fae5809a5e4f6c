"""The boundary rule (``signorini.fem.boundary``): Gauss rules on the boundary edges, split where the
problem names a point at which ``u`` is not smooth, graded toward its singular points.

More of the rule (the manufactured problem's edge, the ``H^{1/2}`` norm it gives) is tested with the
true norms in ``tests/fem/norms/test_true.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from signorini.fem.boundary import boundary_breaks, boundary_rule, singular_points
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.problem import ProblemBase

X_SINGULAR, X_BREAK = 0.35, 0.6  # on the bottom edge, inside the mesh edges [1/4, 1/2] and [1/2, 3/4]


class RootOnTheBottomEdge(ProblemBase):
    """A problem naming a singular point and a break point on the bottom edge."""

    def singular_points(self):
        return np.array([[X_SINGULAR], [0.0]])

    def boundary_breaks(self):
        return np.array([[X_BREAK], [0.0]])


def bottom_root_integral(rule, mesh) -> float:
    """∫ of |x₁ − X_SINGULAR|^{1/2} over the bottom edge by the rule (zero on the other edges)."""
    x = rule.points(mesh.p)
    f = np.where(x[1] == 0.0, np.sqrt(np.abs(x[0] - X_SINGULAR)), 0.0)
    return float(np.sum(f * rule.ds))


def test_a_problem_without_points_gets_the_rule_on_whole_edges():
    mesh = friedrichs_keller(4)
    assert singular_points(ProblemBase()).shape == boundary_breaks(ProblemBase()).shape == (2, 0)
    rule = boundary_rule(mesh, ProblemBase(), 5)
    assert rule.edge.size == 4 * 4 and rule.s.shape == (16, 5)  # one piece per boundary edge
    assert rule.ds.sum() == pytest.approx(4.0, rel=1e-14)  # the boundary's length
    assert np.all((rule.s > 0.0) & (rule.s < 1.0))


def test_the_split_rule_integrates_a_root_singularity_to_round_off_where_whole_edges_do_not():
    """The edges holding the named points are cut there (one piece more each); the pieces ending at
    the singular point are graded (s = τ²), which makes r^{1/2} a polynomial in τ."""
    mesh, problem = friedrichs_keller(4), RootOnTheBottomEdge()
    exact = 2.0 / 3.0 * (X_SINGULAR**1.5 + (1.0 - X_SINGULAR) ** 1.5)
    split = boundary_rule(mesh, problem, 12)
    assert split.edge.size == 16 + 2 and split.ds.sum() == pytest.approx(4.0, rel=1e-14)
    assert bottom_root_integral(split, mesh) == pytest.approx(exact, rel=1e-11)
    whole = boundary_rule(mesh, problem, 12, split=False)
    assert whole.edge.size == 16
    assert abs(bottom_root_integral(whole, mesh) / exact - 1.0) > 1e-6
