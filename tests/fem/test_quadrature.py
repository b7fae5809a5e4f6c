"""The quadrature rules behind the norms (``signorini.fem.quadrature``): their degrees of exactness."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.polynomial.legendre import leggauss

from signorini.fem.quadrature import dunavant8, gauss_legendre_01, stroud_conical

# ---------------------------------------------------------------------------------
# quadrature rules
# ---------------------------------------------------------------------------------


def triangle_moment(a: int, b: int) -> float:
    """∫ x^a y^b over the reference triangle (0,0), (1,0), (0,1)."""
    return math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)


def test_dunavant8_has_16_points_and_degree_exactly_8():
    X, W = dunavant8()
    assert X.shape == (2, 16) and W.shape == (16,)
    assert np.all(W > 0) and W.sum() == pytest.approx(0.5, rel=1e-14)
    assert np.all(X >= 0) and np.all(X.sum(axis=0) <= 1)
    for d in range(9):
        for a in range(d + 1):
            assert W @ (X[0] ** a * X[1] ** (d - a)) == pytest.approx(triangle_moment(a, d - a), rel=1e-13, abs=1e-16)
    assert abs(W @ X[0] ** 9 - triangle_moment(9, 0)) > 1e-9


@pytest.mark.parametrize("vertices", [[(0, 0), (1, 0), (0, 1)], [(0.2, 0.1), (0.7, 0.3), (0.1, 0.9)]])
def test_stroud_conical_rule_has_degree_7(vertices):
    """∫_T g ≈ |T| Σ w g(v1 + s (v2 − v1) + s t (v3 − v2)), exact to degree 7 (4 × 4 points)."""
    s, t, w = stroud_conical(4)
    assert s.size == 16 and w.sum() == pytest.approx(1.0, rel=1e-14)
    v1, v2, v3 = (np.array(v, float) for v in vertices)
    x = v1[:, None] + s * (v2 - v1)[:, None] + s * t * (v3 - v2)[:, None]
    e1, e2 = v2 - v1, v3 - v1
    area = 0.5 * abs(e1[0] * e2[1] - e1[1] * e2[0])
    # reference moments on T by a fine Dunavant-free route: a collapsed 12×12 Gauss tensor rule
    gs, gw = leggauss(12)
    gs, gw = (gs + 1) / 2, gw / 2
    S, T = np.meshgrid(gs, gs, indexing="ij")
    Wt = np.outer(gw, gw) * S * 2  # Jacobian of the collapse, normalised so that Σ = 1
    Xr = v1[:, None, None] + S * (v2 - v1)[:, None, None] + S * T * (v3 - v2)[:, None, None]
    worst8 = 0.0
    for d in range(9):
        for a in range(d + 1):
            exact = area * np.sum(Wt * Xr[0] ** a * Xr[1] ** (d - a))
            approx = area * np.sum(w * x[0] ** a * x[1] ** (d - a))
            if d <= 7:
                assert approx == pytest.approx(exact, rel=1e-13, abs=1e-16), (a, d - a)
            else:
                worst8 = max(worst8, abs(approx - exact) / abs(exact))
    assert worst8 > 1e-10, "degree 7, not 8"


@pytest.mark.parametrize("n", [1, 3, 8])
def test_gauss_legendre_01(n):
    x, w = gauss_legendre_01(n)
    assert np.all((x > 0) & (x < 1)) and w.sum() == pytest.approx(1.0, rel=1e-14)
    for k in range(2 * n):
        assert w @ x**k == pytest.approx(1.0 / (k + 1), rel=1e-13)


def test_rules_are_computed_once_and_read_only():
    assert stroud_conical(5) is stroud_conical(5) and gauss_legendre_01(6) is gauss_legendre_01(6)
    for array in (*stroud_conical(5), *gauss_legendre_01(6)):
        with pytest.raises(ValueError):
            array[0] = 0.0

