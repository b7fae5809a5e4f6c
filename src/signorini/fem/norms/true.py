"""The ``<name>_true`` norms: the same norm of ``e = u − u_h`` as ``<name>``, evaluated to a stated
relative accuracy (``RTOL``) instead of with the paper's fixed rules and point sets.

- **Integrals** (``Lp``, ``W1p``, ``H1`` and the one-sided parts): ``e`` is smooth inside each
  triangle except at the problem's singular points (the free point ``(x0, 0)``, where
  ``u ~ r^{3/2}``).  Triangles farther than ``FAR`` diameters from it get an ``n × n`` conical
  Gauss product rule (degree ``2n − 1``).  The triangles near it are sub-triangulated, graded toward
  it, and the innermost pieces become a fan of triangles with apex at the singular point
  (``∫_T = Σ_edges ± ∫_{(P, a, b)}``, with ``u_h`` the affine function of ``T``), each with the
  conical rule collapsed at ``P`` and the radial variable graded as ``s = σ²``: ``r^{k/2}`` becomes
  a polynomial in ``σ``, so the rule converges exponentially despite the singularity.  Every
  triangle ``T`` is integrated at its own rule: all at ``n = 3`` and ``5`` first, and
  ``|I_n(T) − I_n'(T)|`` (its last two rules) estimates the quadrature error of ``I_n(T)`` (it is
  about the error of the lower rule: an over-estimate).  Where u is affine (``hessian_bound``
  zero: beyond the cut-off, u ≡ 0) and the exponent an even integer, the integrand is a
  polynomial of the affine e and its integral has a closed form (``_affine_rule``, difference
  zero).  The estimated quadrature error of ``I = Σ_T I_n(T) = ∫ g(e, ∇e)`` is
  ``E = Σ_T |I_n(T) − I_n'(T)|``, a sum of absolute values, so that no cancellation between
  triangles hides an error.  While ``E`` exceeds the tolerance the triangles of the largest
  differences move to their next rule (``INTEGRAL_LEVELS``); the error sits in few triangles
  (where ``|e|`` is largest and least polynomial), so only those are evaluated again.  The
  stated error of the norm is ``I^{1/p} − (I − E)^{1/p}``, converged when at most ``rtol`` of it.
- **Maxima** (``Linf``, ``W1inf``) where the derivatives of u are bounded (``hessian_bound``,
  ``gradient_holder_bound``, ``fem.derivatives``): a branch and bound.  Every triangle is sampled on a lattice (its
  vertices and edge midpoints), and the bounds give how far each function (``|e|``, ``e^±``,
  ``|∂ₖe|``, ``|∇e|``) can exceed its samples on it (``_increments``; ``u_h`` is affine per
  triangle, so the second derivatives of ``e`` are those of ``u``).  A triangle whose upper bound
  is below the largest sample (a value the function takes, so a lower bound of the norm) cannot
  hold the maximum and is dropped; one whose bound is within ``rtol`` of it is settled (its bound
  is kept for the upper bound of the norm); the others are quadrisected, their pieces sampled and
  bounded, and so on until none is left.  The largest sample, raised by a local maximisation
  from it, and the largest bound of the pieces not dropped enclose the norm: converged when they
  agree to ``rtol``, and their difference is its error (a bound, not an estimate, up to
  rounding).  Near the singular point the second derivatives blow up; the pieces that touch it
  are bounded by the Hölder continuity of ``∇u`` instead, never by the Hessian.
  A problem without such bounds: every triangle is sampled on a barycentric lattice (4, 8, 16,
  32 subdivisions per edge, plus the singular points), the candidate triangles (sampled maximum
  within ``CANDIDATE_MARGIN`` of the largest, at most ``MAX_CANDIDATES``) are maximised locally
  (L-BFGS-B in Duffy coordinates), until two levels agree to ``rtol``.
- **Boundary norms** (``H12``, ``L2boundary``): the split and graded boundary rule of
  ``fem.boundary`` with 8, 16, 32, … points per piece, until two levels agree to ``rtol``.

What a norm combines is its definition (``fem.norms.families``): the parts, and for the ``W^{1,p}``
form and the ``H^{1/2}`` formula the ``Conventions`` (they define the norm); the triangle rule and
the point sets do not enter.  Each part enters the integrals as its squared magnitude raised to
``p/2`` (``integer_power``), the maxima as its magnitude.  ``TrueNorm.levels`` records what
each level did (how many triangles it evaluated at which rule, or sampled, settled and kept).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.boundary import singular_points
from signorini.fem.derivatives import derivative_bounds, u_and_grad_u
from signorini.fem.mesh import Triangles
from signorini.fem.norms.conventional import ErrorField, boundary_error, boundary_norm, integer_power, power_scale
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.families import BOUNDARY, MAX, PARTS, VALUE_PARTS, NormDefinition, define, magnitude, part
from signorini.fem.norms.names import NormName, norm_name
from signorini.fem.quadrature import gauss_legendre_01, stroud_conical

if TYPE_CHECKING:
    from skfem import MeshTri

RTOL = 1e-4  # the relative accuracy the levels are refined to
INTEGRAL_LEVELS = (3, 5, 7, 10, 14, 20)  # n of the n × n conical rules of a triangle, level by level
# n of the graded rules of a triangle near the singular point, level by level: the singular
# integrand is far from its asymptotic convergence at n = 3 (the rules 3, 5, 7 need not approach the
# integral monotonically there), so its levels start at 5
NEAR_LEVELS = (5, 7, 10, 14, 20, 28)
REFINE_TARGET = 0.25  # a refinement round aims at E ≤ this fraction of the tolerance
MAX_ROUNDS = 16  # refinement rounds of the integrals at most
BOUND_LEVELS = 64  # quadrisection levels of the branch and bound of the maxima at most
# pieces sampled in one level of the branch and bound at most (memory): enough for a graded mesh,
# whose bounds keep a third of its triangles for two levels (docs/evidence/design-measurements.md#max-pieces)
MAX_PIECES = 1 << 23
LATTICE = 2  # subdivisions per edge of the lattice each piece is sampled on
MAX_LEVELS = (4, 8, 16, 32)  # lattice subdivisions per triangle edge, maxima without bounds
BOUNDARY_LEVELS = (8, 16, 32, 64)  # Gauss points per boundary piece
FAR = 2.0  # a (sub-)triangle this many diameters from the singular point gets the plain rule
FAN = 0.25  # a sub-triangle this close (in diameters) gets the fan rule; in between: quadrisected
MAX_DEPTH = 12
CANDIDATE_MARGIN = 0.1  # triangles whose sampled maximum is within 10 % of the largest
MAX_CANDIDATES = 24
CHUNK = 1 << 14  # triangles per evaluation chunk, bounds memory
EXACT_DISTANCE = 10.0  # triangles within this many diameters of the singular point: exact distances


@dataclass
class TrueNorm:
    """A converged norm value with its estimated quadrature error and the refinement history."""

    name: str
    value: float
    # integrals: the estimate I^{1/p} − (I − E)^{1/p}; maxima with bounds: upper bound − value;
    # otherwise |value of the last level − value of the level before|
    error_estimate: float
    rtol: float
    converged: bool  # error_estimate ≤ rtol · value
    levels: list[dict] = field(default_factory=list)  # {"level": ..., "value": ..., what it evaluated}

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class _Affine:
    """Per triangle: vertices (2, 3, E), ``u_h`` at vertex 0 and ``∇u_h`` (2, E)."""

    v: np.ndarray
    u0: np.ndarray
    grad: np.ndarray

    @classmethod
    def of(cls, mesh: MeshTri, u_h: np.ndarray, elements: np.ndarray) -> _Affine:
        t = mesh.t[:, elements]
        v = mesh.p[:, t]
        j00, j01 = v[0, 1] - v[0, 0], v[0, 2] - v[0, 0]
        j10, j11 = v[1, 1] - v[1, 0], v[1, 2] - v[1, 0]
        det = j00 * j11 - j01 * j10
        d1, d2 = u_h[t[1]] - u_h[t[0]], u_h[t[2]] - u_h[t[0]]
        grad = np.stack([(j11 * d1 - j10 * d2) / det, (-j01 * d1 + j00 * d2) / det])
        return cls(v, u_h[t[0]], grad)

    def take(self, index: np.ndarray) -> _Affine:
        return _Affine(self.v[:, :, index], self.u0[index], self.grad[:, index])

    def error(self, problem, x: np.ndarray, gradient: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """``e`` and (if asked) ``∇e`` at points ``x`` (2, E, q), ``u_h`` the affine function of each triangle."""
        dx = x - self.v[:, 0, :, None]
        uh = self.u0[:, None] + self.grad[0][:, None] * dx[0] + self.grad[1][:, None] * dx[1]
        if not gradient:
            return problem.u(x) - uh, None
        u, du = u_and_grad_u(problem, x)
        return u - uh, du - self.grad[:, :, None]


def _chunks(n: int):
    """Consecutive index ranges of at most ``CHUNK`` of ``range(n)``."""
    for start in range(0, n, CHUNK):
        yield np.arange(start, min(n, start + CHUNK))


def _squared(name: str, e: np.ndarray, de: np.ndarray | None) -> np.ndarray:
    """The squared magnitude of the part ``name``: ``x · x``, and ``∂₁e² + ∂₂e²`` for ``|∇e|``."""
    if name == "grad":
        return de[0] * de[0] + de[1] * de[1]
    x = part(name, e, de)
    return x * x


def _integrand(norm: NormDefinition):
    """``(e, ∇e) ↦`` the integrand whose integral is the norm to the power p (the sum over the
    parts of their squared magnitudes to the power p/2); needs ∇e?"""
    q, parts = norm.p / 2.0, norm.parts

    def integrand(e: np.ndarray, de: np.ndarray | None) -> np.ndarray:
        total = None
        for name in parts:
            term = integer_power(_squared(name, e, de), q)
            total = term if total is None else total + term
        return total

    return integrand, norm.needs_gradient


def _complete_homogeneous(a: np.ndarray, p: int) -> np.ndarray:
    """``h_p(a₀, a₁, a₂) = Σ_{i+j+k=p} a₀^i a₁^j a₂^k`` per column of a (3, K), by
    ``h_n(x₁, …, x_m) = h_n(x₁, …, x_{m−1}) + x_m h_{n−1}(x₁, …, x_m)``."""
    h = [np.ones_like(a[0])]
    for _ in range(p):
        h.append(h[-1] * a[0])
    for var in a[1:]:
        for n in range(1, p + 1):
            h[n] = h[n] + var * h[n - 1]
    return h[p]


def _affine_rule(norm: NormDefinition, integrand, scale: float):
    """The exact integral over the triangles where u (so e) is affine, or None when the integrand is
    not a polynomial there (a one-sided part, an exponent that is not an even integer).  With
    ``aᵢ = e(vᵢ)``, ``(Σ λᵢ aᵢ)^p`` expanded by the multinomial theorem and
    ``∫_T λ₀^i λ₁^j λ₂^k = 2|T| i! j! k! / (i + j + k + 2)!`` give
    ``∫_T e^p = 2|T| h_p(a₀, a₁, a₂) / ((p + 1)(p + 2))``; ``∇e`` is constant on T.  Exact up to
    rounding: the terms of h_p may have both signs, and Hunter's inequality
    ``h_{2k}(a) ≥ |a|^{2k} / (2^k k!)`` bounds the cancellation."""
    if norm.one_sided or not float(norm.p / 2.0).is_integer():
        return None
    p, has_value = int(norm.p), "e" in norm.parts

    def exact(problem, aff: _Affine) -> np.ndarray:
        e = (problem.u(aff.v) - (aff.u0 + np.einsum("dk,dik->ik", aff.grad, aff.v - aff.v[:, :1]))) / scale
        jac = (aff.v[0, 1] - aff.v[0, 0]) * (aff.v[1, 2] - aff.v[1, 0]) - (aff.v[0, 2] - aff.v[0, 0]) * (
            aff.v[1, 1] - aff.v[1, 0]
        )
        area = 0.5 * np.abs(jac)
        value = 2.0 * area * _complete_homogeneous(e, p) / ((p + 1) * (p + 2)) if has_value else 0.0
        if not norm.needs_gradient:
            return value
        centroid = aff.v.mean(axis=1)[:, :, None]
        de = (problem.grad_u(centroid)[:, :, 0] - aff.grad) / scale
        return value + area * integrand(np.zeros(area.size), de)

    return exact


def _diameters(v: np.ndarray) -> np.ndarray:
    """Longest edge of each triangle (vertices (2, 3, K))."""
    return np.max([np.hypot(*(v[:, i] - v[:, (i + 1) % 3])) for i in range(3)], axis=0)


def _distance(v: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Distance of the point q (2,) to each closed triangle (vertices (2, 3, K))."""
    d = np.full(v.shape[2], np.inf)
    for i in range(3):
        a, b = v[:, i], v[:, (i + 1) % 3]
        ab = b - a
        s = np.clip(np.sum((q[:, None] - a) * ab, axis=0) / np.sum(ab * ab, axis=0), 0.0, 1.0)
        d = np.minimum(d, np.hypot(*(a + s * ab - q[:, None])))
    cross = [
        (v[0, (i + 1) % 3] - v[0, i]) * (q[1] - v[1, i]) - (v[1, (i + 1) % 3] - v[1, i]) * (q[0] - v[0, i])
        for i in range(3)
    ]
    inside = (np.min(cross, axis=0) >= 0.0) | (np.max(cross, axis=0) <= 0.0)
    return np.where(inside, 0.0, d)


def _quadrisect(v: np.ndarray) -> np.ndarray:
    """The four children (2, 3, 4K) of each triangle, by its edge midpoints."""
    m01, m12, m20 = (v[:, 0] + v[:, 1]) / 2, (v[:, 1] + v[:, 2]) / 2, (v[:, 2] + v[:, 0]) / 2
    kids = [(v[:, 0], m01, m20), (m01, v[:, 1], m12), (m20, m12, v[:, 2]), (m12, m20, m01)]
    return np.concatenate([np.stack(k, axis=1) for k in kids], axis=2)


def _graded(v: np.ndarray, apex: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The graded sub-triangulation of triangles ``v`` (2, 3, K) toward ``apex``: pieces at least
    ``FAR`` diameters away (vertices, parent index), and pieces within ``FAN`` diameters of the
    apex (vertices, parent index), which get the fan rule; the others are quadrisected."""
    parent = np.arange(v.shape[2])
    far_v, far_p, fan_v, fan_p = [], [], [], []
    for depth in range(MAX_DEPTH + 1):
        ratio = _distance(v, apex) / _diameters(v)
        far, fan = ratio >= FAR, ratio <= FAN
        if depth == MAX_DEPTH:
            fan = ~far
        far_v.append(v[:, :, far])
        far_p.append(parent[far])
        fan_v.append(v[:, :, fan])
        fan_p.append(parent[fan])
        rest = ~(far | fan)
        if not rest.any():
            break
        v, parent = _quadrisect(v[:, :, rest]), np.tile(parent[rest], 4)
    return (np.concatenate(far_v, axis=2), np.concatenate(far_p), np.concatenate(fan_v, axis=2), np.concatenate(fan_p))


def _rule_integrals(problem, aff: _Affine, integrand, gradient: bool, n: int, v: np.ndarray) -> np.ndarray:
    """The n × n conical rule (degree 2n − 1) on each triangle v (2, 3, K); ``aff`` holds the
    affine ``u_h`` of each triangle's element."""
    s, t, w = stroud_conical(n)
    X = np.vstack([s * (1.0 - t), s * t])
    jac = np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]], axis=1)  # (2, 2, K)
    x = v[:, 0, :, None] + np.einsum("dke,kq->deq", jac, X)
    det = np.abs(jac[0, 0] * jac[1, 1] - jac[0, 1] * jac[1, 0])
    e, de = aff.error(problem, x, gradient)
    return (integrand(e, de) @ w) * (det / 2.0)


def _fan_integrals(
    problem, aff: _Affine, integrand, gradient: bool, n: int, v: np.ndarray, apex: np.ndarray
) -> np.ndarray:
    """∫_T of each triangle v as the signed fan of triangles (apex, a, b) over the edges (a, b) of T,
    each with the conical rule collapsed at the apex and graded as s = σ²."""
    sig, ws = gauss_legendre_01(n)
    tt, wt = gauss_legendre_01(n)
    S, T = np.meshgrid(sig, tt, indexing="ij")
    W = np.outer(ws, wt).ravel() * 4.0 * S.ravel() ** 3  # dA = 2|A| s ds dt, s = σ²
    S2, T = S.ravel() ** 2, T.ravel()
    area_T = 0.5 * ((v[0, 1] - v[0, 0]) * (v[1, 2] - v[1, 0]) - (v[0, 2] - v[0, 0]) * (v[1, 1] - v[1, 0]))
    total = np.zeros(v.shape[2])
    for k in range(3):
        a, b = v[:, k], v[:, (k + 1) % 3]
        pa, ab = a - apex[:, None], b - a
        area = 0.5 * (pa[0] * ab[1] - pa[1] * ab[0]) * np.sign(area_T)  # signed, T counted positive
        x = apex[:, None, None] + S2[None, None, :] * (pa[:, :, None] + T[None, None, :] * ab[:, :, None])
        e, de = aff.error(problem, x, gradient)
        total += (integrand(e, de) @ W) * area
    return total


@dataclass
class _NearField:
    """The elements within ``FAR`` diameters of the singular point (sorted indices, a mask over all
    elements) and their graded sub-triangulation (``_graded``: pieces with their parent's index
    into ``elements``), which each rule integrates piece by piece."""

    apex: np.ndarray
    elements: np.ndarray
    mask: np.ndarray
    aff: _Affine
    far_v: np.ndarray
    far_p: np.ndarray
    fan_v: np.ndarray
    fan_p: np.ndarray

    @classmethod
    def of(cls, problem, mesh: MeshTri, u_h: np.ndarray, mask: np.ndarray) -> _NearField | None:
        """The near field of the elements ``mask`` marks (``_survey``); None without a singular point."""
        points = singular_points(problem)
        if not points.shape[1]:
            return None
        apex = points[:, 0]
        elements = np.flatnonzero(mask)
        pieces = _graded(mesh.p[:, mesh.t[:, elements]], apex)
        return cls(apex, elements, mask, _Affine.of(mesh, u_h, elements), *pieces)

    def integrals(self, problem, integrand, gradient: bool, n: int) -> np.ndarray:
        """The integral over each near element at rule n (its pieces summed)."""
        k = self.elements.size
        far = _rule_integrals(problem, self.aff.take(self.far_p), integrand, gradient, n, self.far_v)
        fan = _fan_integrals(problem, self.aff.take(self.fan_p), integrand, gradient, n, self.fan_v, self.apex)
        return np.bincount(self.far_p, far, minlength=k) + np.bincount(self.fan_p, fan, minlength=k)


def _radii(problem, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A lower bound of the distance of each triangle v (2, 3, K) to the singular point, and the
    largest distance (inf for a problem that names none).  The lower bound is the distance itself
    for the triangles within ``EXACT_DISTANCE`` diameters, and ``minᵢ |vᵢ − P| − diameter`` beyond
    (every point lies within a diameter of each vertex): at most a tenth below it."""
    points = singular_points(problem)
    if not points.shape[1]:
        return np.full(v.shape[2], np.inf), np.full(v.shape[2], np.inf)
    q = points[:, 0]
    vertex = np.hypot(v[0] - q[0, None], v[1] - q[1, None])  # (3, K)
    nearest, diameter = vertex.min(axis=0), _diameters(v)
    r_lo = np.maximum(nearest - diameter, 0.0)
    close = nearest < EXACT_DISTANCE * diameter
    r_lo[close] = _distance(v[:, :, close], q)
    return r_lo, vertex.max(axis=0)


def _survey(problem, mesh: MeshTri, u_h: np.ndarray, gradient: bool) -> tuple[float, np.ndarray, np.ndarray | None]:
    """One pass over the elements: a power of two near the largest |e| (and |∇e|) at the element
    centroids (the integrands' powers |e / scale|^p then neither overflow nor underflow:
    ``norms.power_scale``); per element whether it lies within ``FAR`` diameters of the singular
    point (the near field; its distance exact there: ``FAR + 1 < EXACT_DISTANCE``); and, where the
    problem bounds its derivatives, whether u is affine on it (``hessian_bound`` zero; else None)."""
    if singular_points(problem).shape[1] > 1:  # the grading is toward one point
        raise ValueError("the true norms handle at most one singular point")
    bounds, n_el, scales = derivative_bounds(problem), mesh.t.shape[1], []
    near, affine = np.zeros(n_el, dtype=bool), None if bounds is None else np.zeros(n_el, dtype=bool)
    compiled = _compiled_survey(problem, mesh, u_h, gradient)
    for el in _chunks(n_el):
        if compiled is None:
            aff = _Affine.of(mesh, u_h, el)
            e, de = aff.error(problem, aff.v.mean(axis=1)[:, :, None], gradient)
            scales.append(power_scale(e if de is None else np.concatenate([e.ravel(), de.ravel()])))
            r_lo, r_hi = _radii(problem, aff.v)
            diameter = _diameters(aff.v)
        else:
            largest, r_lo, r_hi, diameter = compiled(int(el[0]), el.size)
            scales.append(power_scale(largest))
        near[el] = r_lo < FAR * diameter
        if affine is not None:
            affine[el] = np.asarray(bounds.hessian_bound(r_lo, r_hi)) == 0.0
    return max(scales, default=1.0), near, affine


def _compiled_survey(problem, mesh, u_h: np.ndarray, gradient: bool):
    """``(start, count) ↦`` what ``_survey`` reads of the triangles ``start, …, start + count − 1``
    (the largest ``|e|``, and ``|∂ₖe|``, at each centroid; ``_radii``; ``_diameters``), the same bits
    in one pass of the problem's compiled kernel (``fem.norms.kernels.manufactured_survey``); None
    where the problem has none enabled."""
    params = problem.point_kernel()
    if params is None:
        return None
    from signorini.fem.norms import kernels  # numba: only where the problem's kernel is enabled

    p, t = np.ascontiguousarray(mesh.p, dtype=float), np.ascontiguousarray(mesh.t)
    u_h = np.ascontiguousarray(u_h, dtype=float)

    def survey(start: int, count: int) -> tuple[np.ndarray, ...]:
        out = tuple(np.empty(count) for _ in range(4))
        kernels.manufactured_survey(p[0], p[1], t, start, u_h, *params, EXACT_DISTANCE, gradient, *out)
        return out

    return survey


@dataclass(frozen=True)
class _CompiledRule:
    """The plain rule of ``_rule_integrals`` on the triangles of a mesh, in the problem's compiled point
    kernel (``ExactProblem.point_kernel``; ``fem.norms.kernels.manufactured_rule_integrals``): one
    pass over the points of each triangle, no arrays of them.  The same operations per point; the sum
    over a triangle's points runs in order where numpy's matrix–vector product takes its own (the
    integrals agree to round-off, ``docs/evidence/design-measurements.md#compiled-norm-kernels``)."""

    mesh: Triangles
    u_h: np.ndarray
    params: tuple[float, ...]
    scale: float
    parts: np.ndarray
    q: float
    gradient: bool

    @classmethod
    def of(cls, problem, mesh, u_h: np.ndarray, norm: NormDefinition, scale: float) -> _CompiledRule | None:
        """The compiled rule of ``norm``'s integrand ``(e / scale, ∇e / scale)``, or None where the
        problem has no compiled kernel enabled."""
        params = problem.point_kernel()
        if params is None:
            return None
        triangles = Triangles(np.ascontiguousarray(mesh.p, dtype=float), np.ascontiguousarray(mesh.t))
        parts = np.array([PARTS.index(name) for name in norm.parts], dtype=np.int64)
        return cls(triangles, np.ascontiguousarray(u_h), params, scale, parts, norm.p / 2.0, norm.needs_gradient)

    def integrals(self, elements: np.ndarray, n: int) -> np.ndarray:
        """The n × n conical rule's integral over each of ``elements``."""
        from signorini.fem.norms import kernels  # numba: only where the problem's kernel is enabled

        s, t, w = stroud_conical(n)
        out = np.empty(elements.size)
        kernels.manufactured_rule_integrals(
            self.mesh.p[0], self.mesh.p[1], self.mesh.t, np.ascontiguousarray(elements), self.u_h,
            np.ascontiguousarray(s * (1.0 - t)), np.ascontiguousarray(s * t), np.ascontiguousarray(w),
            *self.params, self.scale, self.parts, kernels.squarings(self.q), self.q, self.gradient, out,
        )  # fmt: skip
        return out


def _integrals(
    problem, mesh, u_h, integrand, gradient: bool, levels, elements: np.ndarray, near, exact=None, compiled=None
):
    """∫ over each of ``elements`` (k,) at each of ``levels`` (R, k): the conical rule of
    ``INTEGRAL_LEVELS`` (``compiled``: in the problem's kernel, ``_CompiledRule``), or the graded rule
    of ``near`` (``NEAR_LEVELS``) for the elements near the singular point, or (R equal rows) the
    closed form of ``exact`` = (``_affine_rule``, the mask of ``_survey``) on the elements where u is
    affine."""
    out = np.empty((len(levels), elements.size))
    near_values = None
    if near is not None and near.mask[elements].any():
        near_values = [near.integrals(problem, integrand, gradient, NEAR_LEVELS[k]) for k in levels]
    for chunk in _chunks(elements.size):
        el = elements[chunk]
        is_near = np.zeros(el.size, dtype=bool) if near is None else near.mask[el]
        affine = np.zeros(el.size, dtype=bool)
        if exact is not None:
            rule, affine_mask = exact
            affine = ~is_near & affine_mask[el]
            if affine.any():
                out[:, chunk[affine]] = rule(problem, _Affine.of(mesh, u_h, el[affine]))
        plain = ~(is_near | affine)
        plain_at = chunk[plain]
        plain_aff = None if compiled is not None else _Affine.of(mesh, u_h, el[plain])
        for i, k in enumerate(levels):
            n = INTEGRAL_LEVELS[k]
            if compiled is not None:
                out[i, plain_at] = compiled.integrals(el[plain], n)
            else:
                out[i, plain_at] = _rule_integrals(problem, plain_aff, integrand, gradient, n, plain_aff.v)
            if is_near.any():
                out[i, chunk[is_near]] = near_values[i][np.searchsorted(near.elements, el[is_near])]
    return out


def _to_refine(value: np.ndarray, diff: np.ndarray, rule: np.ndarray, tol: float) -> np.ndarray:
    """The elements to move to their next rule: those of the largest differences, until the others'
    differences sum to at most ``REFINE_TARGET · tol`` (all refinable ones if that cannot be reached).
    An element whose difference is below ``REFINE_TARGET · tol / #elements`` is never needed."""
    target = REFINE_TARGET * tol
    candidates = np.flatnonzero((diff > target / value.size) & (rule < len(INTEGRAL_LEVELS) - 1))
    order = candidates[np.argsort(-diff[candidates], kind="stable")]
    rest = diff.sum() - np.cumsum(diff[order])
    return np.sort(order[: int(np.searchsorted(-rest, -target)) + 1])


def _integral_level(
    level: int, total: float, estimate: float, p: float, scale: float, rule, near, evaluated: int
) -> dict:
    """A level of an integral norm: its value, the estimated error of the value (from the estimate
    ``estimate`` of the integral's error), how many elements it evaluated and how many are at each
    rule (those near the singular point apart: their graded rules)."""
    value = max(total, 0.0) ** (1.0 / p) * scale
    error = None if estimate == np.inf else float(value - max(total - estimate, 0.0) ** (1.0 / p) * scale)
    near_counts = np.bincount(rule[near.elements] if near is not None else rule[:0], minlength=len(NEAR_LEVELS))
    counts = np.bincount(rule, minlength=len(INTEGRAL_LEVELS)) - near_counts
    return {
        "level": level,
        "value": float(value),
        "error_estimate": error,
        "evaluated": int(evaluated),
        "elements_per_rule": {str(n): int(c) for n, c in zip(INTEGRAL_LEVELS, counts, strict=True)},
        "near_elements_per_rule": {str(n): int(c) for n, c in zip(NEAR_LEVELS, near_counts, strict=True)},
    }


def _integral_norm(problem, mesh, u_h, norm: NormDefinition, rtol: float) -> TrueNorm:
    """Every element at the first two rules (exactly where u is affine), then rounds of moving the
    elements of the largest differences to their next rule until ``E`` is within the tolerance of
    the integral that makes the norm's error at most ``rtol`` (module docstring)."""
    plain, gradient = _integrand(norm)
    scale, near_mask, affine_mask = _survey(problem, mesh, u_h, gradient)  # e / scale is exact

    def integrand(e: np.ndarray, de: np.ndarray | None) -> np.ndarray:  # (norm / scale)^p, in range
        return plain(e / scale, None if de is None else de / scale)

    near, n_el, p = _NearField.of(problem, mesh, u_h, near_mask), mesh.t.shape[1], norm.p
    rule = None if affine_mask is None else _affine_rule(norm, plain, scale)
    exact = None if rule is None else (rule, affine_mask)
    compiled = _CompiledRule.of(problem, mesh, u_h, norm, scale)
    value, diff, lower = np.empty(n_el), np.empty(n_el), 0.0
    for block in range(0, n_el, 64 * CHUNK):  # blocks bound the memory of the two rules' values
        el = np.arange(block, min(n_el, block + 64 * CHUNK))
        both = _integrals(problem, mesh, u_h, integrand, gradient, (0, 1), el, near, exact, compiled)
        value[el], diff[el], lower = both[1], np.abs(both[1] - both[0]), lower + float(both[0].sum())
    rule = np.zeros(n_el, dtype=np.int8)
    levels = [_integral_level(0, lower, np.inf, p, scale, rule, near, n_el)]
    rule[:] = 1
    levels.append(_integral_level(1, float(value.sum()), float(diff.sum()), p, scale, rule, near, n_el))
    for level in range(2, MAX_ROUNDS + 2):
        total = float(value.sum())
        tol = max(total, 0.0) * (1.0 - (1.0 - rtol) ** p)  # E ≤ tol ⟺ error of the norm ≤ rtol · norm
        pick = _to_refine(value, diff, rule, tol) if float(diff.sum()) > tol else np.zeros(0, dtype=int)
        if not pick.size:
            break
        for k in np.unique(rule[pick]):
            el = pick[rule[pick] == k]
            new = _integrals(problem, mesh, u_h, integrand, gradient, (k + 1,), el, near, compiled=compiled)[0]
            diff[el], value[el], rule[el] = np.abs(new - value[el]), new, k + 1
        levels.append(_integral_level(level, float(value.sum()), float(diff.sum()), p, scale, rule, near, pick.size))
    last = levels[-1]
    return TrueNorm(norm.name.name, last["value"], last["error_estimate"], rtol, _within(last, rtol), levels)


def _within(level: dict, rtol: float) -> bool:
    return level["error_estimate"] <= rtol * abs(level["value"])


def _settled(levels: list[dict], rtol: float) -> bool:
    return len(levels) >= 2 and abs(levels[-1]["value"] - levels[-2]["value"]) <= rtol * abs(levels[-1]["value"])


def _result(name: str, levels: list[dict], rtol: float) -> TrueNorm:
    value = levels[-1]["value"]
    estimate = abs(value - levels[-2]["value"]) if len(levels) >= 2 else float("inf")
    return TrueNorm(name, value, estimate, rtol, _settled(levels, rtol), levels)


def true_norm(
    problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    name: str | NormName,
    conventions: Conventions | None = None,
    rtol: float = RTOL,
) -> TrueNorm:
    """The norm ``name`` (with or without the ``_true`` suffix) of ``u − u_h`` to relative accuracy ``rtol``."""
    norm = define(norm_name(name), conventions)
    u_h = np.asarray(u_h, dtype=float)
    if norm.combination == BOUNDARY:
        return _boundary_norm(problem, mesh, u_h, norm, conventions or Conventions(), rtol)
    if norm.combination == MAX:
        if _bounded(problem):
            return _bounded_max_norm(problem, mesh, u_h, norm, rtol)
        return _sampled_max_norm(problem, mesh, u_h, norm, rtol)
    return _integral_norm(problem, mesh, u_h, norm, rtol)


# --- maxima -------------------------------------------------------------------------------


def _max_functions(norm: NormDefinition):
    """The functions of ``(e, ∇e)`` whose largest value over Ω is the norm (the magnitudes of its
    parts), the kind of each (``"value"``: a convex 1-Lipschitz function of e; ``"gradient"``: of
    ∇e), and whether ∇e is needed."""
    funcs = [lambda e, de, name=name: magnitude(name, e, de) for name in norm.parts]
    kinds = ["value" if name in VALUE_PARTS else "gradient" for name in norm.parts]
    return funcs, kinds, norm.needs_gradient


def _bounded(problem) -> bool:
    """Whether the derivatives of u are bounded (``fem.derivatives.derivative_bounds``: the second
    derivatives; with a singular point also the Hölder constant of ∇u), so that the maxima can
    exclude triangles; at most one singular point."""
    return derivative_bounds(problem) is not None and singular_points(problem).shape[1] <= 1


def _interpolation_radius(v: np.ndarray) -> np.ndarray:
    """Per triangle v (2, 3, K): the ρ with ``Σᵢ λᵢ(x) |x − vᵢ|² ≤ ρ²`` on the whole triangle (λ the
    barycentrics of x).  With c the circumcentre and R its radius, ``Σᵢ λᵢ |x − vᵢ|² = R² − |x − c|²``
    (the parallel-axis identity, ``|vᵢ − c| = R``): at most R² where c lies in the triangle (no
    obtuse angle), and ``(L/2)²`` otherwise (the point of the triangle nearest to c is the midpoint
    of the longest edge L).  Since ``minᵢ |x − vᵢ|² ≤ Σᵢ λᵢ |x − vᵢ|²``, every point lies within ρ of
    a vertex."""
    sq = np.stack([np.sum((v[:, (i + 1) % 3] - v[:, (i + 2) % 3]) ** 2, axis=0) for i in range(3)])
    longest = sq.max(axis=0)
    obtuse = 2.0 * longest >= sq.sum(axis=0)  # L² ≥ a² + b² (right angles: both formulas agree)
    area = 0.5 * np.abs((v[0, 1] - v[0, 0]) * (v[1, 2] - v[1, 0]) - (v[0, 2] - v[0, 0]) * (v[1, 1] - v[1, 0]))
    with np.errstate(divide="ignore", invalid="ignore"):
        circum = np.sqrt(sq[0] * sq[1] * sq[2]) / (4.0 * area)
    return np.where(obtuse, np.sqrt(longest) / 2.0, circum)


def _increments(problem, v: np.ndarray, region: np.ndarray) -> dict[str, np.ndarray]:
    """How far a function of each kind can exceed its largest vertex value on each triangle of the
    shape of v (2, 3, K) inside the triangle ``region`` (2, 3, K), where the derivatives are bounded.

    Let M bound ‖D²u‖₂ on the region (``hessian_bound``; D²e = D²u, u_h being affine) and ρ be
    the ``_interpolation_radius`` of v.  ``"value"`` (g(e), g convex and 1-Lipschitz): with Ie the linear
    interpolant of e at the vertices, Taylor's formula at x toward each vertex, weighted by λᵢ(x)
    (``Σ λᵢ (vᵢ − x) = 0``), gives ``|e(x) − Ie(x)| ≤ (M/2) Σ λᵢ |x − vᵢ|² ≤ (M/2) ρ²``, and
    ``g(Ie(x)) ≤ maxᵢ g(e(vᵢ))`` by convexity.  ``"gradient"`` (|∂ₖe|, |∇e|, 1-Lipschitz in ∇e):
    every point lies within ρ of a vertex, so it exceeds the vertex value by at most ``M ρ``.  A
    region that touches the singular point has M = ∞; the Hölder bound
    ``|∇u(x) − ∇u(y)| ≤ H |x − y|^{1/2}`` (``gradient_holder_bound``, H for the points within the
    region's largest distance to the singular point) gives instead ``H ρ^{1/2}`` and, with the
    remainder ``(2/3) H |x − vᵢ|^{3/2}`` of Taylor's formula and Jensen's inequality,
    ``(2/3) H ρ^{3/2}``.  The smaller of the two bounds of each kind holds."""
    rho, (r_lo, r_hi), bounds = _interpolation_radius(v), _radii(problem, region), derivative_bounds(problem)
    holder = np.full(rho.shape, np.inf)
    if singular_points(problem).shape[1]:
        holder = np.broadcast_to(np.asarray(bounds.gradient_holder_bound(r_hi), dtype=float), rho.shape)
    hessian = np.broadcast_to(np.asarray(bounds.hessian_bound(r_lo, r_hi), dtype=float), rho.shape)
    return {
        "value": np.minimum(0.5 * hessian * rho**2, 2.0 / 3.0 * holder * rho**1.5),
        "gradient": np.minimum(hessian * rho, holder * np.sqrt(rho)),
    }


def _piece_bounds(problem, mesh, u_h, v: np.ndarray, parent: np.ndarray, funcs, kinds, gradient: bool):
    """Per piece (vertices v (2, 3, K) inside the elements ``parent``, whose ``u_h`` it uses): the
    largest value of the functions on its lattice of ``LATTICE`` subdivisions (a lower bound of the
    norm), an upper bound of the functions over it, and that sample's point (2, K) and function.
    The lattice splits the piece into ``LATTICE²`` triangles congruent to it scaled by ``1/LATTICE``
    (translated, or turned by 180°), whose vertices are the lattice points: the ``_increments`` of
    that shape, with the derivatives bounded on the piece, bound the excess over the samples."""
    X = _lattice(LATTICE)
    aff = _Affine.of(mesh, u_h, parent)
    x = v[:, 0, :, None] + np.einsum("dke,kq->deq", np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]], axis=1), X)
    e, de = aff.error(problem, x, gradient)  # (K, q)
    copy = v[:, :1] + (v - v[:, :1]) / LATTICE  # one of them: the increments depend on the shape only
    increments = _increments(problem, copy, v)
    values = np.stack([f(e, de) for f in funcs], axis=1)  # (K, F, q)
    samples = values.max(axis=2)
    bounds = [samples[:, i] + increments[kind] for i, kind in enumerate(kinds)]
    flat = np.argmax(values.reshape(values.shape[0], -1), axis=1)
    point = x[:, np.arange(parent.size), flat % X.shape[1]]
    return samples.max(axis=1), np.max(bounds, axis=0), point, flat // X.shape[1]


@dataclass
class _Best:
    """The largest sample so far: its value, and the element, point and function of it."""

    value: float = 0.0  # every function is ≥ 0
    element: int = -1
    point: np.ndarray | None = None
    func: int = 0

    def offer(self, sample: np.ndarray, point: np.ndarray, func: np.ndarray, parent: np.ndarray) -> None:
        k = int(np.argmax(sample))
        if sample[k] > self.value:
            self.value, self.element, self.func = float(sample[k]), int(parent[k]), int(func[k])
            self.point = point[:, k].copy()

    def polished(self, problem, mesh, u_h, funcs, gradient: bool) -> float:
        """The value raised by a local maximisation from its point over its element (``_local_max``):
        still a value the function takes, so still a lower bound of the norm."""
        if self.element < 0:
            return self.value
        aff = _Affine.of(mesh, u_h, np.array([self.element]))
        start = np.clip(_reference(aff, self.point)[:, 0], 0.0, 1.0)
        return max(self.value, _local_max(problem, aff, funcs[self.func], gradient, start))


def _max_level(level: int, sampled: int, active: np.ndarray, settled: tuple[int, float], best: float) -> dict:
    """A level of the branch and bound: the largest sample (the value), the largest bound of the
    pieces not dropped (the upper bound), how many pieces it sampled, how many it settled (their
    bound within rtol of the value) and how many it keeps to quadrisect."""
    upper = max(float(active.max(initial=best)), settled[1], best)
    return {
        "level": level,
        "value": best,
        "upper": upper,
        "sampled": int(sampled),
        "settled": int(settled[0]),
        "kept": int(active.size),
    }


def _bounded_max_norm(problem, mesh, u_h, norm: NormDefinition, rtol: float) -> TrueNorm:
    """The branch and bound (module docstring): level 0 samples every element on its lattice,
    each further level quadrisects the pieces kept and samples the children.  A piece is dropped
    when its upper bound is below the largest sample so far (it cannot hold the maximum), settled
    when its bound is within ``rtol`` of it (its bound enters the upper bound, the piece is not
    refined: the largest sample only grows), and kept otherwise; the levels stop when none is kept.
    The value is the largest sample, raised by a local maximisation from it (``_Best.polished``)."""
    funcs, kinds, gradient = _max_functions(norm)
    n_el, best = mesh.t.shape[1], _Best()
    bound = np.empty(n_el)
    for el in _chunks(n_el):
        v = mesh.p[:, mesh.t[:, el]]
        sample, bound[el], point, func = _piece_bounds(problem, mesh, u_h, v, el, funcs, kinds, gradient)
        best.offer(sample, point, func, el)
    parent, v, settled, levels = np.arange(n_el), None, 0.0, []
    for level in range(BOUND_LEVELS + 1):
        if level:
            v, parent = _quadrisect(v), np.tile(parent, 4)
            bound = np.empty(parent.size)
            for chunk in _chunks(parent.size):
                args = (v[:, :, chunk], parent[chunk], funcs, kinds, gradient)
                sample, bound[chunk], point, func = _piece_bounds(problem, mesh, u_h, *args)
                best.offer(sample, point, func, parent[chunk])
        sampled, top = bound.size, best.value
        done = (bound >= top) & (bound <= top * (1.0 + rtol))
        settled = max(settled, float(bound[done].max(initial=0.0)))
        keep = np.flatnonzero(bound > top * (1.0 + rtol))
        parent, bound = parent[keep], bound[keep]
        v = mesh.p[:, mesh.t[:, parent]] if v is None else v[:, :, keep]
        levels.append(_max_level(level, sampled, bound, (int(done.sum()), settled), top))
        if not parent.size or 4 * parent.size > MAX_PIECES:
            break
    upper, value = levels[-1]["upper"], best.polished(problem, mesh, u_h, funcs, gradient)
    levels.append({"level": "local maximum", "value": value, "upper": upper})
    estimate = max(upper - value, 0.0)
    return TrueNorm(norm.name.name, value, estimate, rtol, estimate <= rtol * value, levels)


def _lattice(m: int) -> np.ndarray:
    """Reference coordinates (2, q) of the barycentric lattice with m subdivisions per edge."""
    i, j = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
    keep = i + j <= m
    return np.vstack([i[keep], j[keep]]).astype(float) / m


def _physical(aff: _Affine, X: np.ndarray) -> np.ndarray:
    """Points (2, E, q) of reference coordinates X (2, q) in every triangle of ``aff``."""
    v = aff.v
    jac = np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]], axis=1)
    return v[:, 0, :, None] + np.einsum("dke,kq->deq", jac, X)


def _reference(aff: _Affine, x: np.ndarray) -> np.ndarray:
    """Reference coordinates (2, E) of one point x (2,) in every triangle of ``aff``."""
    v = aff.v
    a, b = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    d = x[:, None] - v[:, 0]
    det = a[0] * b[1] - a[1] * b[0]
    return np.stack([(d[0] * b[1] - d[1] * b[0]) / det, (a[0] * d[1] - a[1] * d[0]) / det])


def _sample_maxima(problem, mesh, u_h, funcs, gradient: bool, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Per function and triangle: the largest sampled value (F, E) and its reference point (2, F, E);
    the lattice of m subdivisions, plus the singular points on the triangles that contain them."""
    X = _lattice(m)
    n_el = mesh.t.shape[1]
    best, where = np.full((len(funcs), n_el), -np.inf), np.zeros((2, len(funcs), n_el))
    for start in range(0, n_el, CHUNK):
        el = np.arange(start, min(n_el, start + CHUNK))
        aff = _Affine.of(mesh, u_h, el)
        e, de = aff.error(problem, _physical(aff, X), gradient)
        for i, f in enumerate(funcs):
            vals = f(e, de)
            k = np.argmax(vals, axis=1)
            best[i, el], where[:, i, el] = vals[np.arange(el.size), k], X[:, k]
    aff = _Affine.of(mesh, u_h, np.arange(n_el))
    for q in singular_points(problem).T:
        ref = _reference(aff, q)
        inside = np.flatnonzero((ref.min(axis=0) >= -1e-12) & (ref.sum(axis=0) <= 1.0 + 1e-12))
        sub = _Affine(aff.v[:, :, inside], aff.u0[inside], aff.grad[:, inside])
        e, de = sub.error(problem, np.broadcast_to(q[:, None, None], (2, inside.size, 1)), gradient)
        for i, f in enumerate(funcs):
            vals = f(e, de)[:, 0]
            better = vals > best[i, inside]
            best[i, inside[better]] = vals[better]
            where[:, i, inside[better]] = np.clip(ref[:, inside[better]], 0.0, 1.0)
    return best, where


def _local_max(problem, aff: _Affine, f, gradient: bool, start: np.ndarray) -> float:
    """The maximum of f over one triangle by L-BFGS-B in Duffy coordinates (s, t) ∈ [0, 1]²
    (ξ = s (1 − t), η = s t), started at the reference point ``start``."""
    from scipy.optimize import minimize

    def neg(st: np.ndarray) -> float:
        xi = np.array([[st[0] * (1.0 - st[1])], [st[0] * st[1]]])
        e, de = aff.error(problem, _physical(aff, xi), gradient)
        return -float(f(e, de)[0, 0])

    s0 = float(start.sum())
    st0 = np.array([s0, start[1] / s0 if s0 > 0 else 0.5])
    res = minimize(neg, st0, method="L-BFGS-B", bounds=[(0.0, 1.0), (0.0, 1.0)], options={"ftol": 1e-15})
    return max(-float(res.fun), -neg(st0))


def _sampled_max_norm(problem, mesh, u_h, norm: NormDefinition, rtol: float) -> TrueNorm:
    """Without bounds of the derivatives: lattices of every triangle and local maximisation on the
    candidates (module docstring), until two levels agree to ``rtol``."""
    funcs, _, gradient = _max_functions(norm)
    levels: list[dict] = []
    for m in MAX_LEVELS:
        best, where = _sample_maxima(problem, mesh, u_h, funcs, gradient, m)
        top = best.max()
        pairs = np.argwhere(best >= (1.0 - CANDIDATE_MARGIN) * top)
        pairs = pairs[np.argsort(-best[pairs[:, 0], pairs[:, 1]])][:MAX_CANDIDATES]
        value = float(top)
        for i, el in pairs:
            aff = _Affine.of(mesh, u_h, np.array([el]))
            value = max(value, _local_max(problem, aff, funcs[i], gradient, where[:, i, el]))
        levels.append({"level": m, "value": value, "candidates": int(len(pairs))})
        if _settled(levels, rtol):
            break
    return _result(norm.name.name, levels, rtol)


# --- boundary norms -----------------------------------------------------------------------


def _boundary_norm(problem, mesh, u_h, norm: NormDefinition, conv: Conventions, rtol: float) -> TrueNorm:
    """The paper's formula (``conventional.boundary_norm``) at 8, 16, 32, … points per boundary piece."""
    levels: list[dict] = []
    for n in BOUNDARY_LEVELS:
        eb, dteb, ds = boundary_error(problem, mesh, u_h, n)
        trace = ErrorField(None, None, None, None, None, None, eb, dteb, ds, conv)
        levels.append({"level": n, "value": boundary_norm(trace, norm)})
        if _settled(levels, rtol):
            break
    return _result(norm.name.name, levels, rtol)
