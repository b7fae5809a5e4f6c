"""Exact norms of a P1 function (an algebraic error ``u_h^solver − u_h^exact``).

For a piecewise linear ``v`` the paper's norms need no quadrature error: ``∫_T v^p`` for even
integer ``p`` is a complete homogeneous polynomial of the vertex values, ``∇v`` is constant per
triangle, maxima are attained at vertices, and ``v`` is linear along every boundary edge.  What
a norm combines is its definition (``fem.norms.families``); here each part is integrated exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.mesh import boundary_edges
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.families import BOUNDARY, GRADIENT_PARTS, MAX, SQUARES, NormDefinition, define, magnitude
from signorini.fem.norms.names import NormName, norm_name

if TYPE_CHECKING:
    from collections.abc import Sequence

    from skfem import MeshTri


def _complete_homogeneous(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, p: int) -> np.ndarray:
    """h_p(v0, v1, v2) = Σ_{a+b+c=p} v0^a v1^b v2^c (elementwise), in O(p) array operations:
    h_m(v0, v1) = v0 h_{m-1}(v0, v1) + v1^m, then h_p = Σ_c v2^c h_{p-c}(v0, v1) by Horner."""
    two = [np.ones_like(v0)]  # h_m(v0, v1), m = 0..p
    power1 = np.ones_like(v1)
    for _ in range(p):
        power1 = power1 * v1
        two.append(v0 * two[-1] + power1)
    out = two[0].copy()
    for m in range(1, p + 1):
        out = out * v2 + two[m]
    return out


def _triangle_power_integrals(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, area: np.ndarray, p: float) -> float:
    """Σ_T ∫_T |v|^p for the linear function with vertex values (v0, v1, v2) on each T.

    Even integer ``p``: exact, ∫_T v^p = 2|T| h_p(v0, v1, v2) / ((p + 1)(p + 2)) (expand
    (Σ vᵢλᵢ)^p and integrate the barycentric monomials).  Otherwise the 64-point conical
    Gauss rule (degree 15).
    """
    if float(p).is_integer() and int(p) % 2 == 0:
        k = int(p)
        return float(np.sum(2.0 * area * _complete_homogeneous(v0, v1, v2, k)) / ((k + 1) * (k + 2)))
    from signorini.fem.quadrature import stroud_conical

    s, t, w = stroud_conical(8)
    lam = np.vstack([1.0 - s, s * (1.0 - t), s * t])  # barycentrics of the conical points (sum 1)
    values = np.outer(v0, lam[0]) + np.outer(v1, lam[1]) + np.outer(v2, lam[2])
    return float(np.sum(area[:, None] * np.abs(values) ** p * w[None, :]))


@dataclass
class _P1Data:
    """A normalised P1 function on a mesh: vertex values per triangle, areas, gradients."""

    mesh: MeshTri
    w: np.ndarray  # nodal values / scale
    w0: np.ndarray
    w1: np.ndarray
    w2: np.ndarray
    area: np.ndarray
    g1: np.ndarray  # ∂₁v per triangle
    g2: np.ndarray

    @classmethod
    def of(cls, mesh: MeshTri, w: np.ndarray) -> _P1Data:
        p, t = mesh.p, mesh.t
        j00, j01 = p[0, t[1]] - p[0, t[0]], p[0, t[2]] - p[0, t[0]]
        j10, j11 = p[1, t[1]] - p[1, t[0]], p[1, t[2]] - p[1, t[0]]
        det = j00 * j11 - j01 * j10
        d1, d2 = w[t[1]] - w[t[0]], w[t[2]] - w[t[0]]
        g1 = (j11 * d1 - j10 * d2) / det
        g2 = (-j01 * d1 + j00 * d2) / det
        return cls(mesh, w, w[t[0]], w[t[1]], w[t[2]], 0.5 * np.abs(det), g1, g2)

    def power(self, q: float) -> float:
        """∫_Ω |v|^q."""
        return _triangle_power_integrals(self.w0, self.w1, self.w2, self.area, q)

    def integral(self, parts: tuple[str, ...], q: float) -> float:
        """``Σ_parts ∫_Ω |part|^q``: ``∫ |v|^q`` for the part ``e``, then the parts of ``∇v`` (constant
        per triangle) summed per triangle and integrated as one term."""
        terms = [self.power(q) for name in parts if name == "e"]
        gradient = None
        for name in parts:
            if name in GRADIENT_PARTS:
                term = magnitude(name, None, (self.g1, self.g2)) ** q
                gradient = term if gradient is None else gradient + term
        if gradient is not None:
            terms.append(float(np.sum(self.area * gradient)))
        total = terms[0]
        for term in terms[1:]:
            total = total + term
        return total

    def maximum(self, name: str) -> float:
        """``max |part|``: at a vertex (1 for ``e``: the function is normalised) or on a triangle."""
        return 1.0 if name == "e" else float(magnitude(name, None, (self.g1, self.g2)).max())

    def boundary(self) -> tuple[float, float]:
        """‖v‖_{L²(∂Ω)} (exact: ∫_e v² = |e| (a² + ab + b²)/3) and |v|_{H¹(∂Ω)} (∂_t v constant per edge)."""
        facets = boundary_edges(self.mesh)
        a, b = self.w[facets[0]], self.w[facets[1]]
        length = np.linalg.norm(self.mesh.p[:, facets[1]] - self.mesh.p[:, facets[0]], axis=0)
        l2 = math.sqrt(float(np.sum(length * (a * a + a * b + b * b) / 3.0)))
        semi = math.sqrt(float(np.sum((b - a) ** 2 / length)))
        return l2, semi


def _root_sum_of_squares(values: list[float]) -> float:
    """``(Σ values²)^{1/2}`` (``hypot``) of norms; one norm as it is."""
    return values[0] if len(values) == 1 else math.hypot(*values)


def _geometric_mean(values: list[float]) -> float:
    """``(Π values)^{1/n}`` of norms of the normalised function (no under- or overflow)."""
    if len(values) == 1:
        return values[0]
    return math.sqrt(values[0] * values[1]) if len(values) == 2 else math.prod(values) ** (1.0 / len(values))


def _norm_of_normalised(f: _P1Data, norm: NormDefinition) -> float:
    """One norm of the normalised function (max |v| = 1 at the vertices)."""
    if norm.combination == BOUNDARY:
        l2, semi = f.boundary()
        norms = {"e": l2, "dt": semi}
        return _geometric_mean([_root_sum_of_squares([norms[name] for name in factor]) for factor in norm.factors])
    if norm.one_sided:
        raise ValueError(f"p1_norms: norm {norm.name.name!r} is not supported (plus/minus parts)")
    if norm.combination == MAX:
        return max(f.maximum(name) for name in norm.parts)
    total = f.integral(norm.parts, norm.p)
    return math.sqrt(total) if norm.combination == SQUARES else total ** (1.0 / norm.p)


def p1_norms(
    mesh: MeshTri, v: np.ndarray, names: Sequence[str | NormName], conventions: Conventions | None = None
) -> dict[str, float]:
    """The named norms of the P1 function with nodal values ``v`` (an algebraic error).

    Exact for a piecewise linear function: ``Lp`` (even integer ``p``; other ``p`` by a
    degree-15 rule), ``Linf`` (max over the vertices), ``W1p``/``W1inf`` in the form
    ``conventions.w1p_form`` (∇v is constant per triangle), ``H1``, ``L2boundary`` and
    ``H12`` (``conventions.h12_form``).  The point-set conventions of ``Linf``/``W1inf`` do
    not matter: the maxima of a P1 function are attained at vertices.  ``plus``/``minus``
    parts are not supported.
    """
    conv = conventions or Conventions()
    specs = [norm_name(name) for name in names]  # unknown names raise UnknownNormError
    v = np.asarray(v, dtype=float)
    scale = float(np.abs(v).max(initial=0.0))
    if scale == 0.0 or not np.isfinite(scale):
        return {spec.name: 0.0 if scale == 0.0 else math.nan for spec in specs}
    data = _P1Data.of(mesh, v / scale)  # normalised: no under-/overflow in high powers
    return {spec.name: scale * float(_norm_of_normalised(data, define(spec, conv))) for spec in specs}
