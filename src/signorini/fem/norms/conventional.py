"""Norms of the error ``e = u - u_h`` under the paper's conventions: fixed rules and point sets.

All norms of one mesh are computed from one ``ErrorField``: the values of ``e``
and ``∇e`` at the points of the triangle rule (and at the vertices and edge
midpoints of every triangle for the maxima), plus ``e`` and ``∂_t e`` at
Gauss points of the boundary edges.  A norm is requested by name (``fem.norms.names``);
what it combines is its definition (``fem.norms.families``), and here each part is reduced
under the conventions (``fem.norms.conventions``):

============  =====================================================================================
``P_SUM``     ``(Σ_parts ∫ |part|^p)^{1/p}`` by the triangle rule ``Conventions.quadrature``:
              ``s (Σ w |part / s|^p)^{1/p}`` with a power of two ``s``, the integer powers by
              squarings shared between the norms of one field (``PowerCache``)
``SQUARES``   the same with ``p = 2`` (``H1``)
``MAX``       the largest ``|part|`` over the point set ``Conventions.linf_points`` (``Linf``)
              or ``Conventions.w1inf_points`` (``W1inf``)
``BOUNDARY``  the ``L²(∂Ω)`` norms of ``e`` and ``∂_t e`` by Gauss–Legendre on the pieces of the
              boundary edges, split at the free point and at ``x0 ± R`` (``fem.boundary``), and the
              geometric mean of the factors (``H12``: ``Conventions.h12_form``)
============  =====================================================================================

The same norms evaluated to a stated accuracy, with an error estimate, are the ``<name>_true``
norms of ``fem.norms.true``; ``fem.norms.evaluate.evaluate_named_norms`` takes a list of both kinds.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import reduce
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.boundary import boundary_rule
from signorini.fem.derivatives import u_and_grad_u
from signorini.fem.mesh import triangles_meeting_disc
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.families import BOUNDARY, MAX, PARTS, NormDefinition, define, magnitude, part
from signorini.fem.norms.names import NormName, UnknownNormError, norm_name
from signorini.fem.problem import Problem, compiled_points_enabled
from signorini.fem.quadrature import dunavant8, stroud_conical

# scikit-fem is slow to import (docs/evidence/design-measurements.md#lazy-imports); only type hints need it here
if TYPE_CHECKING:
    from skfem import MeshTri

BOUNDARY_POINTS = 8  # Gauss–Legendre points per piece of a boundary edge (fem.boundary)

__all__ = ["Conventions", "ErrorField", "UnknownNormError", "error_field", "evaluate_norms", "parse_norm"]


@dataclass
class ErrorField:
    """``e``, ``∂₁e``, ``∂₂e`` at quadrature points (weights ``dx``), at max points, and on ∂Ω.

    Parts a norm does not need may be ``None`` (see ``error_field(..., norms=...)``).
    """

    e: np.ndarray
    de: np.ndarray  # (2, ...) gradient at quadrature points
    dx: np.ndarray
    e_max: np.ndarray  # e at the L^∞ point set
    de_max: np.ndarray  # ∇e at the W^{1,∞} point set (per triangle)
    e_w1: np.ndarray  # e at the W^{1,∞} point set
    eb: np.ndarray  # e at boundary Gauss points
    dteb: np.ndarray  # tangential derivative ∂_t e at boundary Gauss points
    dsb: np.ndarray  # boundary weights
    conventions: Conventions
    powers: PowerCache = field(default_factory=lambda: PowerCache(), repr=False, compare=False)

    def part(self, name: str) -> np.ndarray:
        """The array at the quadrature points of the part ``name`` (``fem.norms.families.PARTS``)."""
        return part(name, self.e, self.de)

    def max_magnitude(self, name: str, points: str) -> np.ndarray:
        """``|part|`` at the point set of the conventions' field ``points`` (``linf_points``: ``e`` alone
        there; ``w1inf_points``: ``e`` and ``∇e``)."""
        e, de = (self.e_max, None) if points == "linf_points" else (self.e_w1, self.de_max)
        return magnitude(name, e, de)

    def boundary_part(self, name: str) -> np.ndarray:
        """The array at the boundary Gauss points of the part ``name`` (``fem.norms.families.BOUNDARY_PARTS``):
        the trace ``e`` or its tangential derivative ``dt``."""
        return {"e": self.eb, "dt": self.dteb}[name]


class PowerCache:
    """The magnitudes ``|x|`` of one error field's arrays and the squarings ``|x / s|^(2^j)`` of
    ``integer_power``, kept while the norms being evaluated share them: ``L2`` … ``L32`` reduce the
    squarings of one chain, and so do ``W12`` … ``W132``.  Only one group of arrays (with its scale)
    is kept at a time, so at most one chain's arrays are held; each power is the product
    ``integer_power`` forms, bit for bit."""

    def __init__(self) -> None:
        self.group: tuple = ()
        self.store: dict = {}

    def enter(self, names: tuple[str, ...], scale: float) -> None:
        """Keep the arrays of the group ``names`` reduced at ``scale``: another group's go."""
        if self.group != (names, scale):
            self.group = (names, scale)
            self.store = {key: v for key, v in self.store.items() if key[0] == "abs" and key[1] in names}

    def magnitude(self, f: ErrorField, name: str) -> tuple[np.ndarray, float]:
        """``|x|`` and its maximum."""
        if ("abs", name) not in self.store:
            a = np.abs(f.part(name))
            self.store["abs", name] = (a, float(np.max(a, initial=0.0)))
        return self.store["abs", name]

    def power(self, f: ErrorField, name: str, scale: float, p: float) -> np.ndarray:
        """``|x / scale|^p`` (``integer_power``'s value), the squarings kept for the next p."""
        a = self.magnitude(f, name)[0]
        if not float(p).is_integer() or p < 1:
            return (a / scale) ** p

        def square(j: int) -> np.ndarray:  # a loop, not a recursion: no reference cycle holds ``a``
            store = self.store
            for i in range(j + 1):
                if ("sq", name, i) not in store:
                    below = store["sq", name, i - 1] if i else None
                    store["sq", name, i] = a / scale if i == 0 else below * below
            return store["sq", name, j]

        return power_from_squarings(int(p), square)


@functools.cache
def _reference_rule(quadrature: str) -> tuple[np.ndarray, np.ndarray, int | None]:
    """Reference points/weights (read-only: computed once per process); for Stroud rules also
    which vertex role is collapsed."""
    if quadrature == "dunavant8":
        X, W = dunavant8()
        role = None
    else:
        s, t, w = stroud_conical(4)
        # collapsed vertex is local vertex 0: barycentrics (1 - s, s (1 - t), s t)
        X, W = np.vstack([s * (1.0 - t), s * t]), w / 2.0
        role = {"stroud4_right": 0, "stroud4_acute1": 1, "stroud4_acute2": 2}[quadrature]
    X.flags.writeable = W.flags.writeable = False
    return X, W, role


def _rolled_t(p: np.ndarray, t: np.ndarray, role: int) -> np.ndarray:
    """The triangles' vertices rotated so that local vertex 0 is the right-angle vertex
    (role 0) or the next (role 1) / second-next (role 2) counter-clockwise."""
    # right angle: the vertex with the largest angle, i.e. the smallest |dot product| of its edges;
    # at vertex k the edges to the next two vertices: ±(e01·e02), (−e01)·e12, (−e02)·(−e12)
    v0, v1, v2 = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    e01, e02, e12 = v1 - v0, v2 - v0, v2 - v1
    dots = [e01[0] * e02[0] + e01[1] * e02[1], e12[0] * e01[0] + e12[1] * e01[1], e02[0] * e12[0] + e02[1] * e12[1]]
    right = np.argmin(np.abs(np.array(dots)), axis=0)
    # counter-clockwise orientation of (t0, t1, t2)
    ccw = e01[0] * e02[1] - e01[1] * e02[0] > 0
    tt = np.where(ccw, t, t[[0, 2, 1]])
    right = np.where(ccw, right, np.array([0, 2, 1])[right])
    start = (right + role) % 3
    cols = np.arange(t.shape[1])
    return np.vstack([tt[(start + k) % 3, cols] for k in range(3)])


def triangle_rule(p: np.ndarray, t: np.ndarray, quadrature: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The conventions' triangle rule ``quadrature`` placed on the triangles ``t``: its reference
    points (2, q) and weights (q,), and the triangles with their vertices in the order that puts
    a Stroud rule's collapsed vertex where the rule names it (``t`` itself for ``dunavant8``)."""
    X, W, role = _reference_rule(quadrature)
    return X, W, t if role is None else _rolled_t(p, t, role)


def _barycentric(X: np.ndarray) -> np.ndarray:
    """The barycentric coordinates (3, q) ``(1 − ξ − η, ξ, η)`` of reference points ``X`` (2, q)."""
    return np.vstack([1.0 - X[0] - X[1], X[0], X[1]])


def p1_at_points(
    p: np.ndarray, t: np.ndarray, u_h: np.ndarray, X: np.ndarray, points: bool = True
) -> tuple[np.ndarray | None, np.ndarray, np.ndarray, np.ndarray]:
    """Points, ``u_h``, ``∇u_h`` and ``|det J|`` at reference points ``X`` (2, q) of every triangle
    (the points None if not ``points``).

    The affine P1 map written out (barycentrics λ = (1 - ξ - η, ξ, η)): scikit-fem's
    ``CellBasis`` does the same in general but builds (3, 2, elements, q) basis arrays, which
    costs far more time and memory per rule than this (docs/evidence/design-measurements.md#p1-at-points).
    Tested against
    ``CellBasis.interpolate`` in tests/fem/norms/test_conventional.py.
    """
    lam = _barycentric(X)  # (3, q)
    v = p[:, t]  # (2, 3, elements)
    x = np.einsum("dke,kq->deq", v, lam) if points else None
    value = u_h[t].T @ lam  # (elements, q)
    j00, j01 = v[0, 1] - v[0, 0], v[0, 2] - v[0, 0]
    j10, j11 = v[1, 1] - v[1, 0], v[1, 2] - v[1, 0]
    det = j00 * j11 - j01 * j10
    d1, d2 = u_h[t[1]] - u_h[t[0]], u_h[t[2]] - u_h[t[0]]  # ∂u_h/∂ξ, ∂u_h/∂η
    grad = np.stack([(j11 * d1 - j10 * d2) / det, (-j01 * d1 + j00 * d2) / det])  # J^{-T} ∇̂u_h
    return x, value, grad[:, :, None], np.abs(det)


def exact_at(
    problem: Problem, p: np.ndarray, t: np.ndarray, X: np.ndarray, meet: np.ndarray | None, gradient: bool
) -> tuple[np.ndarray, np.ndarray | None]:
    """``u`` (and ``∇u`` if ``gradient``) at the reference points ``X`` (2, q) of the triangles ``t``:
    evaluated on the triangles ``meet`` marks (all if None), ``+0.0`` on the others (outside the
    problem's ``support``, where ``u`` and ``∇u`` are ``+0.0``), so the values are the ones an
    evaluation everywhere gives, bit for bit, and the points of the other triangles are never formed."""
    tm = t if meet is None else t[:, meet]
    x = np.einsum("dke,kq->deq", p[:, tm], _barycentric(X))  # the points of p1_at_points
    if gradient:
        u, du = u_and_grad_u(problem, x)
    else:  # problem.u: the same operations as u_and_grad_u's value
        u, du = problem.u(x), None
    if meet is None:
        return u, du
    full = np.zeros((t.shape[1], X.shape[1]))
    full[meet] = u
    if du is None:
        return full, None
    dfull = np.zeros((2, t.shape[1], X.shape[1]))
    dfull[:, meet] = du
    return full, dfull


def element_points(which: str) -> np.ndarray:
    """Reference coordinates (2, q) of the per-triangle point set ``which`` of the maxima: the
    vertices, the edge midpoints, or both (``all``, the triangle rule's points apart)."""
    verts = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    mids = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5]])
    return {"vertices": verts, "midpoints": mids}.get(which, np.hstack([verts, mids]))


def boundary_error(
    problem: Problem, mesh: MeshTri, u_h: np.ndarray, n: int, split: bool = True
) -> tuple[np.ndarray, ...]:
    """``e``, ``∂_t e`` and the arclength weights at the points of ``fem.boundary.boundary_rule``
    (``n`` Gauss points per piece of a boundary edge); ``u_h`` is linear along each edge."""
    rule = boundary_rule(mesh, problem, n, split)
    a, b = rule.a[rule.edge], rule.b[rule.edge]
    pa, pb = mesh.p[:, a], mesh.p[:, b]
    length = np.linalg.norm(pb - pa, axis=0)
    xb = rule.points(mesh.p)
    uhb = u_h[a][:, None] * (1.0 - rule.s) + u_h[b][:, None] * rule.s
    ub, dub = u_and_grad_u(problem, xb)
    eb = ub - uhb
    dteb = np.einsum("ie,iek->ek", (pb - pa) / length, dub) - ((u_h[b] - u_h[a]) / length)[:, None]
    return eb, dteb, rule.ds


def _evaluations(norms: Sequence[NormDefinition] | None) -> set[str]:
    """Which evaluations the norms need: quadrature (``e`` and ``∇e`` at the triangle rule),
    values (``e`` alone there), linf, w1inf (the point sets of the maxima), boundary."""
    if norms is None:
        return {"quadrature", "linf", "w1inf", "boundary"}
    needed = set()
    for norm in norms:
        if norm.combination == BOUNDARY:
            needed.add("boundary")
        elif norm.combination == MAX:
            needed.add("w1inf" if norm.points == "w1inf_points" else "linf")
        else:
            needed.add("quadrature" if norm.needs_gradient else "values")
    return needed


def error_field(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    conventions: Conventions | None = None,
    norms: Sequence[str | NormName] | None = None,
    elements: np.ndarray | None = None,
) -> ErrorField:
    """Evaluate ``e = u - u_h`` and ``∇e`` where the norms need them.

    With ``norms`` given, only the evaluations those norms need are made (the
    others are left ``None``; ``∇e`` only for a norm that has it), so one norm can be
    computed on its own cheaply.  ``elements`` restricts the cell evaluations to a subset of
    triangles (the boundary part always covers all of ∂Ω); ``evaluate_norms`` uses it to bound
    memory.
    """
    conv = conventions or Conventions()
    needed = _evaluations(None if norms is None else [define(name, conv) for name in norms])
    return _error_field(problem, mesh, u_h, conv, needed, elements)


def _error_field(
    problem: Problem, mesh: MeshTri, u_h: np.ndarray, conv: Conventions, needed: set[str], elements: np.ndarray | None
) -> ErrorField:
    """``error_field`` of the evaluations ``needed`` (``_evaluations``)."""
    cache: dict[str, tuple | np.ndarray | None] = {}

    t = mesh.t if elements is None else mesh.t[:, elements]

    def error_at(tr: np.ndarray, X: np.ndarray, gradient: bool) -> tuple:
        if "meet" not in cache:  # the triangles that meet the support, once, where a cell evaluation needs them
            support = problem.support()
            cache["meet"] = None if support is None else triangles_meeting_disc(mesh.p, t, support)
        _, uh, duh, det = p1_at_points(mesh.p, tr, u_h, X, points=False)
        u, du = exact_at(problem, mesh.p, tr, X, cache["meet"], gradient)
        return u - uh, None if du is None else du - duh, det

    def at_quadrature(gradient: bool) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        key = "quadrature" if gradient or "quadrature" in cache else "values"
        if key not in cache:
            X, W, tq = triangle_rule(mesh.p, t, conv.quadrature)
            *cache[key], det = error_at(tq, X, gradient)
            cache["dx"] = det[:, None] * W[None, :]
        return (*cache[key], cache["dx"])

    def at_points(which: str, gradient: bool) -> tuple[np.ndarray, np.ndarray | None]:
        if which == "quadrature":
            return at_quadrature(gradient)[:2]
        key = which if gradient or which in cache else f"{which} values"
        if key not in cache:
            pe, pde, _ = error_at(t, element_points(which), gradient)
            if which == "all":
                e, de, _ = at_quadrature(gradient)
                pe = np.concatenate([pe, e], axis=-1)
                pde = None if pde is None else np.concatenate([pde, de], axis=-1)
            cache[key] = (pe, pde)
        return cache[key]

    e = de = dx = e_max = de_max = e_w1 = eb = dteb = dsb = None
    if needed & {"quadrature", "values"}:
        e, de, dx = at_quadrature("quadrature" in needed)
    if "linf" in needed:
        e_max = at_points(conv.linf_points, False)[0]
    if "w1inf" in needed:
        e_w1, de_max = at_points(conv.w1inf_points, True)
    if "boundary" in needed:
        # Gauss–Legendre on every piece of every boundary edge, split (and graded) where u is not smooth
        eb, dteb, dsb = boundary_error(problem, mesh, u_h, BOUNDARY_POINTS)
    return ErrorField(e, de, dx, e_max, de_max, e_w1, eb, dteb, dsb, conv)


# --- the norms ---------------------------------------------------------------------


def _scale_of(top: float) -> float:
    """The power of two ``power_scale`` gives for ``max |values| = top``."""
    return float(2.0 ** np.floor(np.log2(top))) if 0.0 < top < np.inf else 1.0


def power_scale(values: np.ndarray) -> float:
    """A power of two near ``max |values|`` (1 when they vanish): dividing by it is exact, and
    ``|x / scale|^p`` neither overflows nor underflows where ``|x|^p`` would (``A = 10^±12`` and
    ``p = 32``, or any ``p`` at ``A = 10^100``)."""
    return _scale_of(float(np.max(np.abs(values), initial=0.0)))


def power_from_squarings(q: int, square: Callable[[int], np.ndarray]) -> np.ndarray:
    """``x^q`` for a positive integer ``q``: the product of the squarings ``square(j) = x^(2^j)``
    of its set bits, in increasing ``j`` (every integer power of the norms is formed so)."""
    k, j, result = int(q), 0, None
    while k:
        if k & 1:
            result = square(j) if result is None else result * square(j)
        k, j = k >> 1, j + 1
    return result


def integer_power(base: np.ndarray, q: float) -> np.ndarray:
    """``base^q`` for ``base ≥ 0``: by repeated squaring when ``q`` is a positive integer (a few
    products where ``pow`` costs tens of them: ``q = 32`` is five squarings, each adding a rounding),
    else by ``pow``."""
    if not float(q).is_integer() or q < 1:
        return base**q
    chain = [base]

    def square(j: int) -> np.ndarray:
        while len(chain) <= j:
            chain.append(chain[-1] * chain[-1])
        return chain[j]

    return power_from_squarings(int(q), square)


def weighted_sum(values: np.ndarray, weights: np.ndarray | float) -> float:
    """``Σ weights · values``: the dot product of the flattened arrays (one pass, no temporary)."""
    return float(np.dot(values.ravel(), np.broadcast_to(weights, values.shape).ravel()))


def scaled_p_sum(parts: list[np.ndarray], p: float, weights: np.ndarray | float = 1.0) -> float:
    """(Σ weights · Σ_parts |x|^p)^{1/p}, computed as ``s · (Σ weights · Σ |x/s|^p)^{1/p}`` with the
    power of two ``s = power_scale``: the value of the plain formula where that is finite and
    non-zero (to the few roundings of ``integer_power`` for an integer ``p``; exactly for any other
    ``p``, since correctly rounded powers commute with exact scaling), the right one elsewhere."""
    magnitudes = [np.abs(x) for x in parts]
    scale = _scale_of(max((float(np.max(a, initial=0.0)) for a in magnitudes), default=0.0))
    total = reduce(np.add, [integer_power(a / scale, p) for a in magnitudes])
    return weighted_sum(total, weights) ** (1.0 / p) * scale


def field_p_sum(f: ErrorField, names: tuple[str, ...], p: float) -> float:
    """``scaled_p_sum`` of the field's arrays ``names`` (``ErrorField.part``) with the weights ``dx``,
    to the same bits, their magnitudes and squarings shared with the field's other norms
    (``PowerCache``)."""
    scale = _scale_of(max(f.powers.magnitude(f, name)[1] for name in names))
    f.powers.enter(names, scale)
    total = reduce(np.add, [f.powers.power(f, name, scale, p) for name in names])
    return weighted_sum(total, f.dx) ** (1.0 / p) * scale


def boundary_part_norm(f: ErrorField, name: str) -> float:
    """``‖part‖_{L²(∂Ω)}`` of the boundary part ``name``: ``e`` or ``dt`` = ``∂_t e``, edge by edge."""
    return scaled_p_sum([f.boundary_part(name)], 2.0, f.dsb)


def geometric_mean(values: list[float]) -> float:
    """``(Π values)^{1/n}``, at a power of two near the largest: exact scaling, so the product
    neither overflows nor underflows."""
    if len(values) == 1:
        return float(values[0])
    scale = power_scale(np.array(values))
    product = reduce(lambda a, b: a * b, [v / scale for v in values])
    return float((np.sqrt(product) if len(values) == 2 else product ** (1.0 / len(values))) * scale)


def boundary_norm(f: ErrorField, norm: NormDefinition) -> float:
    """A norm on ∂Ω: the geometric mean of its factors, each the root of the sum of squares
    (``hypot``) of the ``L²(∂Ω)`` norms of its parts (``fem.norms.families``: ``L2boundary``, ``H12``)."""
    norms = {name: boundary_part_norm(f, name) for name in norm.boundary_parts}
    factors = [reduce(np.hypot, [norms[name] for name in factor]) for factor in norm.factors]
    return geometric_mean(factors)


def max_norm(f: ErrorField, norm: NormDefinition) -> float:
    """The largest ``|part|`` of the norm's parts over its point set (``Linf``, ``W1inf``)."""
    return float(max(f.max_magnitude(name, norm.points).max() for name in norm.parts))


def field_norm(f: ErrorField, norm: NormDefinition) -> float:
    """The norm ``norm`` (``fem.norms.families``) of the error field."""
    if norm.combination == BOUNDARY:
        return boundary_norm(f, norm)
    if norm.combination == MAX:
        return max_norm(f, norm)
    return field_p_sum(f, norm.parts, norm.p)  # P_SUM, and SQUARES with p = 2


def _definitions(names: Sequence[str | NormName], conv: Conventions) -> dict[str, NormDefinition]:
    """{name: its definition} (all names parsed first); a ``_true`` name raises ``UnknownNormError``:
    those are evaluated by ``fem.norms.true``."""
    specs = [norm_name(name) for name in names]  # reject unknown names before any work
    true = [spec.name for spec in specs if spec.true]
    if true:
        raise UnknownNormError(
            f"{true}: a _true norm is evaluated to a stated accuracy by fem.norms.true "
            "(true_norm, or fem.norms.evaluate.evaluate_named_norms for a mixed list), not under the conventions"
        )
    return {spec.name: define(spec, conv) for spec in specs}


def parse_norm(name: str | NormName) -> Callable[[ErrorField], float]:
    """Map a norm name (``fem.norms.names``) to a function of an ``ErrorField`` (its definition
    under the field's conventions); raises ``UnknownNormError`` (also for a ``_true`` name: those
    are evaluated by ``fem.norms.true``)."""
    spec = norm_name(name)
    if spec.true:
        raise UnknownNormError(f"{spec.name!r} is not a function of an error field: evaluate it with fem.norms.true")
    return lambda f: field_norm(f, define(spec, f.conventions))


def compute_norms(field: ErrorField, names: Sequence[str | NormName]) -> dict[str, float]:
    """The requested norms of one error field, by name."""
    return _compute(field, _definitions(names, field.conventions))


def _compute(field: ErrorField, norms: dict[str, NormDefinition]) -> dict[str, float]:
    values = {name: field_norm(field, norm) for name, norm in norms.items()}
    field.powers.enter((), 1.0)  # the shared powers go with the last norm
    return values


# triangles per evaluation chunk: bounds its error field and shared powers, and keeps the arrays of a
# chunk in the processor's cache (docs/evidence/design-measurements.md#chunk-sizes); numpy, not a
# compiled kernel (docs/evidence/design-measurements.md#compiled-kernels)
CHUNK_ELEMENTS = 1 << 13


def _reduction(norm: NormDefinition) -> tuple[str, float]:
    """How a norm combines over element chunks: ("sum", p) of ‖·‖ᵖ, ("max", 1) or ("boundary", 1)."""
    if norm.combination == BOUNDARY:
        return "boundary", 1.0
    return ("max", 1.0) if norm.combination == MAX else ("sum", float(norm.p))


def evaluate_norms(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    names: Sequence[str | NormName],
    conventions: Conventions | None = None,
    chunk: int = CHUNK_ELEMENTS,
) -> dict[str, float]:
    """The named norms of ``u - u_h`` under the conventions, evaluated over chunks of triangles
    (bounded memory).  All names share the evaluations of one chunk: ``e`` and ``∇e`` at the points
    of each rule are computed once for all the norms that need them, and each value is the one the
    name alone gives, bit for bit (one p-sum alone where ``u ≡ 0`` on a large mesh by ``_p1_norms``,
    to round-off).  A ``_true`` name raises ``UnknownNormError``: those are evaluated by
    ``fem.norms.true`` (``fem.norms.evaluate.evaluate_named_norms`` takes both kinds)."""
    conv = conventions or Conventions()
    norms = _definitions(names, conv)
    reductions = {name: _reduction(norm) for name, norm in norms.items()}
    cell = {n: norms[n] for n, (kind, _) in reductions.items() if kind != "boundary"}
    boundary = {n: norms[n] for n, (kind, _) in reductions.items() if kind == "boundary"}
    out: dict[str, float] = _p1_norms(problem, mesh, u_h, conv, cell)
    cell = {name: norm for name, norm in cell.items() if name not in out}
    if boundary:
        out.update(_compute(_error_field(problem, mesh, u_h, conv, {"boundary"}, None), boundary))
    acc: dict[str, list[float]] = {name: [] for name in cell}  # the value on each chunk
    n_el, needed = mesh.t.shape[1], _evaluations(cell.values())
    for start in range(0, n_el if cell else 0, chunk):
        field = _error_field(problem, mesh, u_h, conv, needed, np.arange(start, min(n_el, start + chunk)))
        for name, value in _compute(field, cell).items():
            acc[name].append(value)
        del field  # before the next chunk's is built: one chunk's arrays at a time
    for name in cell:
        kind, p = reductions[name]
        values = np.array(acc[name])
        out[name] = float(values.max()) if kind == "max" else scaled_p_sum([values], p)
    return {name: out[name] for name in norms}


def _p1_norms(
    problem: Problem, mesh: MeshTri, u_h: np.ndarray, conv: Conventions, norms: dict[str, NormDefinition]
) -> dict[str, float]:
    """The norm of ``norms`` if it is one norm on Ω, ``u ≡ 0`` (the problem's ``support`` empty:
    ``e = −u_h``, a P1 function, e.g. an algebraic error) and the compiled point kernels are enabled
    (a large mesh), by the compiled kernels of ``fem.norms.kernels``: a maximum in one pass of
    ``p1_rule_largest`` over each part of its point set, a p-sum in two (the largest ``|part|``,
    then ``p1_rule_sum`` at a power of two near it); the same operations per point as
    ``error_field`` and ``field_norm``, the sums in their own order.  Several norms share numpy's
    error field instead, which costs less than two passes for each
    (docs/evidence/design-measurements.md#compiled-norm-kernels).  Empty elsewhere."""
    support = problem.support()
    if not (len(norms) == 1 and compiled_points_enabled() and support is not None and support[1] == 0.0):
        return {}
    from signorini.fem.norms import kernels  # numba: only where the compiled kernels are enabled

    ((name, norm),) = norms.items()
    X, W, role = _reference_rule(conv.quadrature)
    p, t = np.ascontiguousarray(mesh.p, dtype=float), np.ascontiguousarray(mesh.t)
    mesh_v = (p[0], p[1], t, np.ascontiguousarray(u_h, dtype=float))
    parts = np.array([PARTS.index(x) for x in norm.parts])

    def largest(points: np.ndarray, placed: int | None) -> float:
        X0, X1 = np.ascontiguousarray(points[0]), np.ascontiguousarray(points[1])
        return kernels.p1_rule_largest(*mesh_v, X0, X1, -1 if placed is None else placed, parts)

    if norm.combination == MAX:  # the point set of the conventions' field: element points, the rule's or both
        which = getattr(conv, norm.points)
        sets = ([] if which == "quadrature" else [(element_points(which), None)]) + (
            [(X, role)] if which in ("quadrature", "all") else []
        )
        return {name: max(largest(points, placed) for points, placed in sets)}
    power = float(norm.p)
    scale = _scale_of(largest(X, role))
    X0, X1, weights = (np.ascontiguousarray(a) for a in (X[0], X[1], W))
    placed = -1 if role is None else role
    total = kernels.p1_rule_sum(
        *mesh_v, X0, X1, weights, placed, parts, kernels.squarings(power), power, scale, np.empty(parts.size)
    )
    return {name: total ** (1.0 / power) * scale}
