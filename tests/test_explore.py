"""The notebooks' helpers (``signorini.explore``) that decide what a scene is compared with."""

from __future__ import annotations

import math

import pytest

from signorini import explore
from signorini.fem.mesh import DEFAULT_DIAGONAL
from signorini.fem.norm_names import parse_norm_name
from signorini.fem.norms import Conventions
from signorini.fem.problem import Problem
from signorini.paper import THEORETICAL_ORDERS, expected_rate

PAPER_NS = [101, 201, 301, 401, 501]


def test_published_values_belong_to_the_papers_scene_only():
    assert explore.published_mismatch(Problem(), DEFAULT_DIAGONAL, Conventions(), PAPER_NS, PAPER_NS) is None
    assert explore.published_mismatch(Problem(A=10), DEFAULT_DIAGONAL, Conventions(), PAPER_NS, PAPER_NS) is None
    others = {
        "problem": (Problem(x0=0.55, R=0.4), DEFAULT_DIAGONAL, Conventions(), PAPER_NS),
        "triangulation": (Problem(), "nw_se", Conventions(), PAPER_NS),
        "conventions": (Problem(), DEFAULT_DIAGONAL, Conventions(linf_points="vertices"), PAPER_NS),
        "meshes": (Problem(), DEFAULT_DIAGONAL, Conventions(), [11, 21, 41]),
    }
    for what, (problem, diagonal, conventions, Ns) in others.items():
        reason = explore.published_mismatch(problem, diagonal, conventions, Ns, PAPER_NS)
        assert reason is not None and what in reason, (what, reason)
    # a subset of the paper's meshes is not the paper's scene either: its regr. slope differs
    assert "meshes" in explore.published_mismatch(Problem(), DEFAULT_DIAGONAL, Conventions(), PAPER_NS[:3], PAPER_NS)


@pytest.mark.parametrize(
    "norm, order",
    [("L2", 2.0), ("L4", 2.0), ("L6", 1.5 + 2 / 6), ("Linf", 1.5), ("W12", 1.0), ("W1inf", 0.5), ("H1", 1.0),
     ("H12", 1.5), ("L4plus", 2.0), ("L4_true", 2.0), ("L2boundary", None)],
)
def test_expected_rate_of_every_family_of_the_grammar(norm, order):
    parse_norm_name(norm)  # in the grammar
    got = expected_rate(norm)
    assert got == (pytest.approx(order) if order is not None else None)
    if norm in THEORETICAL_ORDERS:
        assert math.isclose(THEORETICAL_ORDERS[norm], got)
