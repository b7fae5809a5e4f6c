"""Convergence rates on a coarse sequence (N = 21, 41, 81) and the EOC helpers.

The paper's Table 2 reports regression slopes ≈ 2 for L⁴ and ≈ 1 for W^{1,4}
(ψ and the r^{3/2} singularity limit the rates); the coarse meshes here already
show them (measured: L⁴ 1.96, W^{1,4} 0.97 on both diagonals).
"""

from __future__ import annotations

import numpy as np
import pytest

from signorini.fem.convergence import eoc, regression_slope
from signorini.fem.discrete import build
from signorini.fem.mesh import mesh_width
from signorini.fem.norms.conventional import compute_norms, error_field
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete

SEQUENCE = (21, 41, 81)
NORMS = ["L4", "W14", "W1inf", "H12"]


@pytest.fixture(scope="module", params=["sw_ne", "nw_se"])
def errors(request):
    problem = Problem()
    table = []
    for N in SEQUENCE:
        disc = build(problem, N, request.param)
        res = solve_discrete(disc)
        assert res.certificate.ok
        table.append(compute_norms(error_field(problem, disc.mesh, res.u), NORMS))
    h = np.array([mesh_width(N) for N in SEQUENCE])
    return h, {name: np.array([row[name] for row in table]) for name in NORMS}


def test_l4_rate_is_near_two(errors):
    h, e = errors
    assert np.all(np.diff(e["L4"]) < 0)
    assert regression_slope(h, e["L4"]) == pytest.approx(2.0, abs=0.25)


def test_w14_rate_is_near_one(errors):
    h, e = errors
    assert np.all(np.diff(e["W14"]) < 0)
    assert regression_slope(h, e["W14"]) == pytest.approx(1.0, abs=0.15)


def test_w1inf_and_h12_rates_match_the_paper(errors):
    """Table 2: W^{1,∞} ≈ 0.50 (the r^{1/2} gradient singularity), H^{1/2}(∂Ω) ≈ 1.5."""
    h, e = errors
    assert regression_slope(h, e["W1inf"]) == pytest.approx(0.5, abs=0.1)
    assert regression_slope(h, e["H12"]) == pytest.approx(1.5, abs=0.2)


# --- the helpers themselves ---------------------------------------------------------


def test_eoc_of_exact_powers():
    h = 1.0 / np.array([101, 201, 301, 401, 501])
    out = eoc(h, 3.0 * h**1.5)
    assert np.isnan(out[0])
    np.testing.assert_allclose(out[1:], 1.5, rtol=1e-12)


def test_eoc_is_the_papers_formula():
    h = np.array([0.1, 0.05, 0.02])
    e = np.array([1.0, 0.3, 0.1])
    expected = [np.nan, np.log(0.3 / 1.0) / np.log(0.5), np.log(0.1 / 0.3) / np.log(0.4)]
    np.testing.assert_allclose(eoc(h, e), expected, rtol=1e-14)


def test_regression_slope():
    h = 1.0 / np.array([21, 41, 81, 161])
    assert regression_slope(h, 7.0 * h**2) == pytest.approx(2.0, rel=1e-12)
    # with noise: the least-squares slope of log e against log h
    noisy = 7.0 * h**2 * np.exp(np.array([0.1, -0.1, -0.1, 0.1]))
    x = np.log(h)
    slope = np.polyfit(x, np.log(noisy), 1)[0]
    assert regression_slope(h, noisy) == pytest.approx(slope, rel=1e-12)
    assert isinstance(regression_slope(list(h), list(7.0 * h)), float)


def test_eoc_and_regression_uncertainties_bound_the_change_of_perturbed_errors():
    """Errors moved by at most ``de`` move each EOC and the regression slope by at most the
    propagated uncertainty (first order; the bound is attained by alternating signs)."""
    from signorini.fem.convergence import eoc_uncertainty, regression_uncertainty

    h = 1.0 / np.array([101.0, 201.0, 301.0, 401.0, 501.0])
    e = 0.3 * h**2 * (1 + 0.1 * h)
    de = 1e-9 * e
    du, dr = eoc_uncertainty(h, e, de), regression_uncertainty(h, e, de)
    assert np.isnan(du[0]) and np.all(du[1:] > 0) and dr > 0
    rng = np.random.default_rng(3)
    for signs in [np.array([1, -1, 1, -1, 1.0]), *rng.choice([-1.0, 1.0], size=(20, 5))]:
        moved = e + signs * de
        assert np.all(np.abs(eoc(h, moved)[1:] - eoc(h, e)[1:]) <= du[1:] * (1 + 1e-6))
        assert abs(regression_slope(h, moved) - regression_slope(h, e)) <= dr * (1 + 1e-6)
    alternating = e + np.array([1, -1, 1, -1, 1.0]) * de
    assert np.abs(eoc(h, alternating)[1:] - eoc(h, e)[1:]) == pytest.approx(du[1:], rel=1e-5)
