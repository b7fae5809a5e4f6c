"""The compiled point kernels of the manufactured problem (numba): ``u`` and ``(u, ∇u)`` of
``fem.problem.Problem`` in one pass over the points, where numpy makes some thirty passes with a
temporary array each.

Importing numba and loading these kernels costs a process more than they save below about a
million elements (docs/evidence/design-measurements.md#compiled-point-kernels): ``Problem`` calls
them only inside ``fem.problem.compiled_points`` (the norm evaluators and the theory quantities
enter it through ``compiled_points_for`` for meshes of at least
``fem.problem.COMPILED_MIN_ELEMENTS`` triangles) and otherwise evaluates with numpy.  Each
kernel performs ``Problem._local`` and ``Problem._cutoff``'s operations in their order (no
contraction into fused multiply–adds: numba leaves it off without ``fastmath``), so both paths
give the same bits; the tests compare them.  Compiled once per machine and cached beside this
module.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, inline="always")
def manufactured_point(x, y, x0, R, A, gradient):  # pragma: no cover - compiled
    """``(u, ∂₁u, ∂₂u)`` at one point (the derivatives 0.0 unless ``gradient``); +0.0 outside the
    support ``r < R``."""
    dx = x - x0
    dy = abs(y)
    r = np.sqrt(dx * dx + dy * dy)
    if not r < R:
        return 0.0, 0.0, 0.0
    re = np.sqrt(max(r + dx, 0.0) * 0.5)
    im = np.sqrt(max(r - dx, 0.0) * 0.5)
    ut = -im * (3.0 * re * re - im * im)
    s = min(max(r / R, 0.0), 1.0)
    t = 1.0 - s
    t2 = t * t
    psi = t2 * t2 * t * (126.0 + t * (-420.0 + t * (540.0 + t * (-315.0 + 70.0 * t))))
    value = A * psi * ut
    if not gradient:
        return value, 0.0, 0.0
    dpr = -630.0 * (s * s * s) * (t2 * t2) / (R * R)
    radial = dpr * ut
    return value, A * (radial * dx - 1.5 * psi * im), A * (radial * dy - 1.5 * psi * re)


@numba.njit(cache=True)
def manufactured_u(px, py, x0, R, A, u):  # pragma: no cover - compiled
    """``u`` at the points ``(px, py)`` (flat) into ``u``."""
    for i in range(px.size):
        u[i] = manufactured_point(px[i], py[i], x0, R, A, False)[0]


@numba.njit(cache=True)
def manufactured_u_and_grad(px, py, x0, R, A, u, gx, gy):  # pragma: no cover - compiled
    """``u`` and ``∇u = (gx, gy)`` at the points ``(px, py)`` (flat)."""
    for i in range(px.size):
        u[i], gx[i], gy[i] = manufactured_point(px[i], py[i], x0, R, A, True)
