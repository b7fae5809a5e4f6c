"""Triangle and boundary quadrature rules.

``dunavant8``: the 16-point degree-8 rule that scikit-fem returns for
``intorder=8`` (the default).  ``stroud4``: the 16-point conical product of
4-point Gauss–Jacobi(α=1) × 4-point Gauss–Legendre rules (degree 7) that Matlab's
``triquad(4, v)`` builds; it collapses one vertex of the triangle, selected by
``collapse`` ∈ {"right", "acute1", "acute2"} (the right-angle vertex or one of the two 45° vertices
of a Friedrichs–Keller triangle, in counter-clockwise order after the right angle).
"""

from __future__ import annotations

import functools

import numpy as np

TRIANGLE_RULES = ("dunavant8", "stroud4_right", "stroud4_acute1", "stroud4_acute2")


def dunavant8() -> tuple[np.ndarray, np.ndarray]:
    """Reference points (2, 16) and weights (16,) (summing to 1/2) of scikit-fem's intorder=8 rule
    (tabulated bit for bit: ``fem.quadrature_tables``)."""
    from signorini.fem.quadrature_tables import DUNAVANT8_POINTS, DUNAVANT8_WEIGHTS

    return _floats(DUNAVANT8_POINTS).reshape(2, -1), _floats(DUNAVANT8_WEIGHTS)


def _floats(hexes: tuple[str, ...]) -> np.ndarray:
    return np.array([float.fromhex(x) for x in hexes])


def roots_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.special.roots_legendre(n)``: tabulated for the rules the norms use (a job that
    evaluates norms then imports neither SciPy nor scikit-fem, most of its time:
    docs/evidence/design-measurements.md#lazy-imports), else SciPy's."""
    from signorini.fem.quadrature_tables import LEGENDRE

    if n in LEGENDRE:
        return _floats(LEGENDRE[n][0]), _floats(LEGENDRE[n][1])
    from scipy.special import roots_legendre as scipy_roots

    return scipy_roots(n)


def roots_jacobi01(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.special.roots_jacobi(n, 0, 1)`` (weight 1 + x on [-1, 1]): tabulated like
    ``roots_legendre``."""
    from signorini.fem.quadrature_tables import JACOBI01

    if n in JACOBI01:
        return _floats(JACOBI01[n][0]), _floats(JACOBI01[n][1])
    from scipy.special import roots_jacobi

    return roots_jacobi(n, 0.0, 1.0)


def _read_only(*arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """The arrays, marked read-only (a cached rule is shared by every caller)."""
    for a in arrays:
        a.flags.writeable = False
    return arrays


@functools.cache  # the true norms ask for a rule once per chunk of triangles
def stroud_conical(n: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Barycentric-style data of the conical product rule: (s, t, w) on the unit square, read-only
    (computed once per process).

    A point (s, t) maps to ``v1 + s (v2 - v1) + s t (v3 - v2)``; ``s`` carries the
    Jacobian, hence Gauss–Jacobi with weight ``s`` on [0, 1].  Weights sum to 1
    (multiply by twice the triangle area... by the area |T| · 2 · 1/2).
    """
    xj, wj = roots_jacobi01(n)  # weight (1 + x) on [-1, 1]
    s, ws = (xj + 1.0) / 2.0, wj / 4.0  # ∫_0^1 s g(s) ds
    xl, wl = roots_legendre(n)
    t, wt = (xl + 1.0) / 2.0, wl / 2.0
    S, T = np.meshgrid(s, t, indexing="ij")
    Wq = np.outer(ws, wt)
    # weights sum to 1 (the area factor is applied per triangle)
    return _read_only(S.ravel(), T.ravel(), 2.0 * Wq.ravel())


@functools.cache
def gauss_legendre_01(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n-point Gauss–Legendre rule on [0, 1] (the boundary line rule), read-only (computed once per
    process)."""
    x, w = roots_legendre(n)
    return _read_only((x + 1.0) / 2.0, w / 2.0)
