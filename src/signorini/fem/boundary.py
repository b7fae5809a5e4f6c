"""Quadrature on the boundary edges of a mesh, split where ``u`` is not smooth.

The manufactured ``u`` has an ``r^{3/2}`` singularity at the free point ``(x0, 0)``, which lies
inside a boundary edge for odd ``N``: on the bottom edge ``u`` is ``A ψ(r) r^{3/2}`` to its left
and 0 to its right, so ``∂_t u`` has an ``r^{1/2}`` kink there, and the cut-off ``ψ`` joins 0 with
``C⁴`` smoothness at ``x0 ± R``.  A Gauss rule over an edge that contains such a point converges
slowly; here every edge is split at those points, and on a piece that ends at the singular point
the Gauss variable is graded as ``s = τ²`` toward it, which turns ``r^{k/2}`` into a polynomial in
``τ`` (the rule is then exact or exponentially convergent on each piece).

A problem names its points by two of its capabilities (``fem.problem.ExactProblem``; none by default):
``singular_points()`` → (2, k) points where ``u`` is not smooth (split and graded) and
``boundary_breaks()`` → (2, k) further points on ∂Ω where ``u`` is less smooth (split only).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.mesh import boundary_edges
from signorini.fem.quadrature import gauss_legendre_01

if TYPE_CHECKING:
    from skfem import MeshTri

    from signorini.fem.problem import ExactProblem

ON_EDGE_TOL = 1e-12  # a point this close (relative to the edge length) lies on the edge


def singular_points(problem: ExactProblem) -> np.ndarray:
    """The problem's singular points as a float array (2, k)."""
    return np.asarray(problem.singular_points(), dtype=float).reshape(2, -1)


def boundary_breaks(problem: ExactProblem) -> np.ndarray:
    """The problem's further break points on ∂Ω as a float array (2, k)."""
    return np.asarray(problem.boundary_breaks(), dtype=float).reshape(2, -1)


@dataclass
class BoundaryRule:
    """Points on the boundary edges: ``edge`` (pieces,) indexes the edges ``a → b``; ``s`` (pieces, n)
    is the parameter along the edge (``x = p_a + s (p_b − p_a)``), ``ds`` the weights in
    arclength (summing to the boundary length)."""

    a: np.ndarray
    b: np.ndarray
    edge: np.ndarray
    s: np.ndarray
    ds: np.ndarray

    def points(self, p: np.ndarray) -> np.ndarray:
        """Physical points (2, pieces, n)."""
        pa, pb = p[:, self.a[self.edge]], p[:, self.b[self.edge]]
        return pa[:, :, None] + (pb - pa)[:, :, None] * self.s[None]


def _params_on_edges(pa: np.ndarray, pb: np.ndarray, points: np.ndarray) -> list[list[float]]:
    """Per edge, the parameters in [0, 1] of the points that lie on it."""
    out: list[list[float]] = [[] for _ in range(pa.shape[1])]
    d = pb - pa
    length2 = np.sum(d * d, axis=0)
    for q in points.T:
        s = np.sum((q[:, None] - pa) * d, axis=0) / length2
        dist = np.hypot(*(pa + np.clip(s, 0.0, 1.0) * d - q[:, None]))
        for k in np.flatnonzero(dist <= ON_EDGE_TOL * np.sqrt(length2)):
            out[k].append(float(np.clip(s[k], 0.0, 1.0)))
    return out


def _pieces(cuts: list[float], graded: list[float]) -> list[tuple[float, float, int]]:
    """Pieces [s0, s1] of [0, 1] between the cuts, with the graded end: 0 none, 1 start, 2 end.
    A piece graded at both ends is halved."""
    knots = sorted({0.0, 1.0, *cuts})
    out = []
    for s0, s1 in zip(knots[:-1], knots[1:], strict=False):
        g0 = any(abs(s0 - g) < ON_EDGE_TOL for g in graded)
        g1 = any(abs(s1 - g) < ON_EDGE_TOL for g in graded)
        if g0 and g1:
            mid = 0.5 * (s0 + s1)
            out += [(s0, mid, 1), (mid, s1, 2)]
        else:
            out.append((s0, s1, 1 if g0 else (2 if g1 else 0)))
    return out


def boundary_rule(mesh: MeshTri, problem: ExactProblem, n: int, split: bool = True) -> BoundaryRule:
    """An ``n``-point Gauss–Legendre rule on every piece of every boundary edge (see the module);
    ``split=False``: on every whole edge (the rule before the split, kept for comparison)."""
    a, b = boundary_edges(mesh)
    pa, pb = mesh.p[:, a], mesh.p[:, b]
    none = np.zeros((2, 0))
    sing = _params_on_edges(pa, pb, singular_points(problem) if split else none)
    brk = _params_on_edges(pa, pb, boundary_breaks(problem) if split else none)
    tau, wt = gauss_legendre_01(n)
    edges, starts, ends, grades = [], [], [], []
    for k in range(a.size):
        for s0, s1, g in _pieces(sing[k] + brk[k], sing[k]) if sing[k] or brk[k] else [(0.0, 1.0, 0)]:
            edges.append(k)
            starts.append(s0)
            ends.append(s1)
            grades.append(g)
    edge, s0, s1, g = (np.array(v) for v in (edges, starts, ends, grades))
    width = (s1 - s0)[:, None]
    # graded toward the start: s = s0 + w τ², ds = 2 w τ dτ; toward the end: mirrored
    t = np.where(g[:, None] == 0, tau[None], tau[None] ** 2)
    dt = np.where(g[:, None] == 0, wt[None], 2.0 * tau[None] * wt[None])
    s = np.where(g[:, None] == 2, s1[:, None] - width * t, s0[:, None] + width * t)
    length = np.linalg.norm(pb - pa, axis=0)[edge][:, None]
    return BoundaryRule(a, b, edge, s, length * width * dt)
