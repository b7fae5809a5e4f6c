"""Norms of the error ``e = u - u_h`` evaluated by quadrature.

All norms of one mesh are computed from one ``ErrorField``: the values of ``e``
and ``∇e`` at the points of the triangle rule (and at the vertices and edge
midpoints of every triangle for the maxima), plus ``e`` and ``∂_t e`` at
Gauss points of the boundary edges.  A norm is requested by name:

=========  =====================================================================
``Lp``     ``(∫ |e|^p)^{1/p}`` for any p ≥ 1 (``L2``, ``L4``, ``L16``, ``L2.5``, …)
``Linf``   ``max |e|`` over the point set ``Conventions.linf_points``
``W1p``    ``W^{1,p}`` norm in the form ``Conventions.w1p_form`` (``W14``, ``W116``)
``W1inf``  ``W^{1,∞}`` norm, same form, maximum over ``Conventions.w1inf_points``
``H1``     ``(‖e‖²_{L²} + ‖∇e‖²_{L²})^{1/2}``
``H12``    ``H^{1/2}(∂Ω)`` estimate by interpolation, ``Conventions.h12_form``; the boundary
           integrals split at the free point and at ``x0 ± R`` (``fem.boundary``)
``L4plus`` / ``L4minus``  ``‖(u - u_h)^±‖_{L⁴}``; any ``Lp`` works with the suffixes
=========  =====================================================================

These are the paper's conventions (``fem.norms.conventions``: fixed rules and point sets).  The same
norms evaluated to a stated accuracy, with an error estimate, are the ``<name>_true`` norms of
``fem.norms.true`` (whose ``evaluate_named_norms`` takes a list of both kinds).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.boundary import boundary_rule
from signorini.fem.derivatives import u_and_grad_u
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.names import UnknownNormError, parse_norm_name
from signorini.fem.problem import Problem
from signorini.fem.quadrature import dunavant8, stroud_conical

if TYPE_CHECKING:  # scikit-fem costs 0.5 s to import; only type hints need it here
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
        """The array at the quadrature points a norm reduces: ``e``, ``e+`` = max(e, 0), ``e-`` =
        max(-e, 0), ``d1``, ``d2`` (the partial derivatives) or ``grad`` = |∇e|."""
        e, de = self.e, self.de
        return {
            "e": lambda: e,
            "e+": lambda: np.maximum(e, 0.0),
            "e-": lambda: np.maximum(-e, 0.0),
            "d1": lambda: de[0],
            "d2": lambda: de[1],
            "grad": lambda: np.hypot(de[0], de[1]),
        }[name]()


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


def _reference_rule(quadrature: str) -> tuple[np.ndarray, np.ndarray, int | None]:
    """Reference points/weights; for Stroud rules also which vertex role is collapsed."""
    if quadrature == "dunavant8":
        X, W = dunavant8()
        return X, W, None
    s, t, w = stroud_conical(4)
    # collapsed vertex is local vertex 0: barycentrics (1 - s, s (1 - t), s t)
    X = np.vstack([s * (1.0 - t), s * t])
    role = {"stroud4_right": 0, "stroud4_acute1": 1, "stroud4_acute2": 2}[quadrature]
    return X, w / 2.0, role


def _rolled_t(p: np.ndarray, t: np.ndarray, role: int) -> np.ndarray:
    """The triangles' vertices rotated so that local vertex 0 is the right-angle vertex
    (role 0) or the next (role 1) / second-next (role 2) counter-clockwise."""
    # right angle: the vertex with the largest angle, i.e. the smallest dot product of its edges
    dots = []
    for k in range(3):
        a, b, c = p[:, t[k]], p[:, t[(k + 1) % 3]], p[:, t[(k + 2) % 3]]
        dots.append(np.sum((b - a) * (c - a), axis=0))
    right = np.argmin(np.abs(np.array(dots)) / 1.0, axis=0)
    # counter-clockwise orientation of (t0, t1, t2)
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    ccw = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0
    tt = np.where(ccw, t, t[[0, 2, 1]])
    right = np.where(ccw, right, np.array([0, 2, 1])[right])
    start = (right + role) % 3
    cols = np.arange(t.shape[1])
    return np.vstack([tt[(start + k) % 3, cols] for k in range(3)])


def p1_at_points(
    p: np.ndarray, t: np.ndarray, u_h: np.ndarray, X: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points, ``u_h``, ``∇u_h`` and ``|det J|`` at reference points ``X`` (2, q) of every triangle.

    The affine P1 map written out (barycentrics λ = (1 - ξ - η, ξ, η)): scikit-fem's
    ``CellBasis`` does the same in general but builds (3, 2, elements, q) basis arrays,
    which at N = 501 costs 3 s and 1 GiB per rule; this costs 0.2 s.  Tested against
    ``CellBasis.interpolate`` in tests/fem/norms/test_conventional.py.
    """
    lam = np.vstack([1.0 - X[0] - X[1], X[0], X[1]])  # (3, q)
    v = p[:, t]  # (2, 3, elements)
    x = np.einsum("dke,kq->deq", v, lam)
    value = u_h[t].T @ lam  # (elements, q)
    j00, j01 = v[0, 1] - v[0, 0], v[0, 2] - v[0, 0]
    j10, j11 = v[1, 1] - v[1, 0], v[1, 2] - v[1, 0]
    det = j00 * j11 - j01 * j10
    d1, d2 = u_h[t[1]] - u_h[t[0]], u_h[t[2]] - u_h[t[0]]  # ∂u_h/∂ξ, ∂u_h/∂η
    grad = np.stack([(j11 * d1 - j10 * d2) / det, (-j01 * d1 + j00 * d2) / det])  # J^{-T} ∇̂u_h
    return x, value, grad[:, :, None], np.abs(det)


def _element_points(mesh: MeshTri, which: str) -> np.ndarray:
    """Reference coordinates of the per-triangle max points: vertices and/or edge midpoints."""
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


def _parts_needed(names: list[str] | None) -> set[str]:
    """Which evaluations the named norms need: quadrature (``e`` and ``∇e`` at the triangle rule),
    values (``e`` alone there: the ``Lp`` norms), linf, w1inf, boundary."""
    if names is None:
        return {"quadrature", "linf", "w1inf", "boundary"}
    parts = set()
    for name in names:
        spec = parse_norm_name(name)  # reject unknown names before any work
        if spec.on_boundary:
            parts.add("boundary")
        elif spec.is_max:
            parts.add("w1inf" if spec.family == "W1" else "linf")
        else:
            parts.add("values" if spec.family == "L" else "quadrature")
    return parts


def error_field(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    conventions: Conventions | None = None,
    norms: list[str] | None = None,
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
    parts = _parts_needed(norms)
    cache: dict[str, tuple] = {}

    t = mesh.t if elements is None else mesh.t[:, elements]

    def error_at(x: np.ndarray, uh: np.ndarray, duh: np.ndarray, gradient: bool) -> tuple:
        if not gradient:  # problem.u: the same operations as u_and_grad_u's value
            return problem.u(x) - uh, None
        u, du = u_and_grad_u(problem, x)
        return u - uh, du - duh

    def at_quadrature(gradient: bool) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        key = "quadrature" if gradient or "quadrature" in cache else "values"
        if key not in cache:
            X, W, role = _reference_rule(conv.quadrature)
            tq = t if role is None else _rolled_t(mesh.p, t, role)
            x, uh, duh, det = p1_at_points(mesh.p, tq, u_h, X)
            cache[key] = error_at(x, uh, duh, gradient)
            cache["dx"] = det[:, None] * W[None, :]
        return (*cache[key], cache["dx"])

    def at_points(which: str, gradient: bool) -> tuple[np.ndarray, np.ndarray | None]:
        if which == "quadrature":
            return at_quadrature(gradient)[:2]
        key = which if gradient or which in cache else f"{which} values"
        if key not in cache:
            x, uh, duh, _ = p1_at_points(mesh.p, t, u_h, _element_points(mesh, which))
            pe, pde = error_at(x, uh, duh, gradient)
            if which == "all":
                e, de, _ = at_quadrature(gradient)
                pe = np.concatenate([pe, e], axis=-1)
                pde = None if pde is None else np.concatenate([pde, de], axis=-1)
            cache[key] = (pe, pde)
        return cache[key]

    e = de = dx = e_max = de_max = e_w1 = eb = dteb = dsb = None
    if parts & {"quadrature", "values"}:
        e, de, dx = at_quadrature("quadrature" in parts)
    if "linf" in parts:
        e_max = at_points(conv.linf_points, False)[0]
    if "w1inf" in parts:
        e_w1, de_max = at_points(conv.w1inf_points, True)
    if "boundary" in parts:
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


def scaled_p_sum(parts: list[np.ndarray], p: float, weights: np.ndarray | float = 1.0) -> float:
    """(Σ weights · Σ_parts |x|^p)^{1/p}, computed as ``s · (Σ weights · Σ |x/s|^p)^{1/p}`` with the
    power of two ``s = power_scale``: the value of the plain formula where that is finite and
    non-zero (to the few roundings of ``integer_power`` for an integer ``p``; exactly for any other
    ``p``, since correctly rounded powers commute with exact scaling), the right one elsewhere."""
    magnitudes = [np.abs(x) for x in parts]
    scale = _scale_of(max((float(np.max(a, initial=0.0)) for a in magnitudes), default=0.0))
    total = sum(integer_power(a / scale, p) for a in magnitudes)
    return float(np.sum(total * weights) ** (1.0 / p) * scale)


def field_p_sum(f: ErrorField, names: tuple[str, ...], p: float) -> float:
    """``scaled_p_sum`` of the field's arrays ``names`` (``ErrorField.part``) with the weights ``dx``,
    to the same bits, their magnitudes and squarings shared with the field's other norms
    (``PowerCache``)."""
    scale = _scale_of(max(f.powers.magnitude(f, name)[1] for name in names))
    f.powers.enter(names, scale)
    total = sum(f.powers.power(f, name, scale, p) for name in names)
    return float(np.sum(total * f.dx) ** (1.0 / p) * scale)


def lp_norm(f: ErrorField, p: float, part: str = "") -> float:
    """(∫ |g|^p)^{1/p} with g = e, e⁺ = max(e, 0) (part "plus") or e⁻ = max(-e, 0) ("minus")."""
    return field_p_sum(f, ({"": "e", "plus": "e+", "minus": "e-"}[part],), p)


def linf_norm(f: ErrorField, part: str = "") -> float:
    """max |e| over the max-point set."""
    g = {"": np.abs(f.e_max), "plus": np.maximum(f.e_max, 0.0), "minus": np.maximum(-f.e_max, 0.0)}[part]
    return float(g.max())


def w1p_norm(f: ErrorField, p: float) -> float:
    """W^{1,p}: components (‖e‖ᵖ + ‖∂₁e‖ᵖ + ‖∂₂e‖ᵖ)^{1/p}, gradient (‖e‖ᵖ + ‖|∇e|‖ᵖ)^{1/p}, or seminorm ‖|∇e|‖_p."""
    parts = {"components": ("e", "d1", "d2"), "gradient": ("e", "grad")}.get(f.conventions.w1p_form, ("grad",))
    return field_p_sum(f, parts, p)


def w1inf_norm(f: ErrorField) -> float:
    """W^{1,∞}: max(|e|, |∂₁e|, |∂₂e|) (components), max(|e|, |∇e|) (gradient) or max |∇e| (seminorm)."""
    form = f.conventions.w1p_form
    if form == "components":
        return float(max(np.abs(f.e_w1).max(), np.abs(f.de_max).max()))
    grad = np.hypot(f.de_max[0], f.de_max[1]).max()
    return float(grad if form == "seminorm" else max(grad, np.abs(f.e_w1).max()))


def h1_norm(f: ErrorField) -> float:
    """(‖e‖²_{L²} + ‖∇e‖²_{L²})^{1/2}."""
    return field_p_sum(f, ("e", "d1", "d2"), 2.0)


def boundary_l2_norm(f: ErrorField) -> float:
    """‖e‖_{L²(∂Ω)}."""
    return scaled_p_sum([f.eb], 2.0, f.dsb)


def boundary_h1_seminorm(f: ErrorField) -> float:
    """|e|_{H¹(∂Ω)} = ‖∂_t e‖_{L²(∂Ω)}, edge by edge."""
    return scaled_p_sum([f.dteb], 2.0, f.dsb)


def h12_interpolation_norm(f: ErrorField) -> float:
    """H^{1/2}(∂Ω) estimate ‖e‖_{1/2} ≤ ‖e‖_{L²(∂Ω)}^{1/2} ‖e‖_{H¹(∂Ω)}^{1/2} (H^{1/2} = [L², H¹]_{1/2});
    with the full H¹(∂Ω) norm (``geometric_full``) or the seminorm (``geometric_semi``)."""
    l2, semi = boundary_l2_norm(f), boundary_h1_seminorm(f)
    h1 = np.hypot(l2, semi) if f.conventions.h12_form == "geometric_full" else semi
    scale = power_scale(np.array([l2, h1]))  # exact: the product neither overflows nor underflows
    return float(np.sqrt((l2 / scale) * (h1 / scale)) * scale)


def parse_norm(name: str):
    """Map a norm name (``fem.norms.names``) to a function of an ``ErrorField``; raises ``UnknownNormError``
    (also for a ``_true`` name: those are evaluated by ``fem.norms.true``)."""
    spec = parse_norm_name(name)
    if spec.true:
        raise UnknownNormError(f"{name!r} is not a function of an error field: evaluate it with fem.norms.true")
    if spec.family == "H12":
        return h12_interpolation_norm
    if spec.family == "H1":
        return h1_norm
    if spec.family == "L2boundary":
        return boundary_l2_norm
    if spec.is_max:
        return (lambda f: linf_norm(f, spec.part)) if spec.family == "L" else w1inf_norm
    p = spec.p
    return (lambda f: lp_norm(f, p, spec.part)) if spec.family == "L" else (lambda f: w1p_norm(f, p))


def compute_norms(field: ErrorField, names: list[str]) -> dict[str, float]:
    """The requested norms of one error field, by name."""
    funcs = {name: parse_norm(name) for name in names}  # validate all names first
    values = {name: fn(field) for name, fn in funcs.items()}
    field.powers.enter((), 1.0)  # the shared powers go with the last norm
    return values


CHUNK_ELEMENTS = 1 << 16  # triangles per evaluation chunk: its error field and shared powers take ~0.25 GiB


def _reduction(name: str) -> tuple[str, float]:
    """How a norm combines over element chunks: ("sum", p) of ‖·‖ᵖ, ("max", 1) or ("boundary", 1)."""
    spec = parse_norm_name(name)
    if spec.on_boundary:
        return "boundary", 1.0
    return ("max", 1.0) if spec.is_max else ("sum", float(spec.p))


def evaluate_norms(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    names: list[str],
    conventions: Conventions | None = None,
    chunk: int = CHUNK_ELEMENTS,
) -> dict[str, float]:
    """The named norms of ``u - u_h`` under the conventions, evaluated over chunks of triangles
    (bounded memory).  All names share the evaluations of one chunk: ``e`` and ``∇e`` at the points
    of each rule are computed once for all the norms that need them, and each value is the one the
    name alone gives, bit for bit.  A ``_true`` name raises ``UnknownNormError``: those are
    evaluated by ``fem.norms.true`` (``evaluate_named_norms`` takes both kinds)."""
    true = [name for name in names if parse_norm_name(name).true]
    if true:
        raise UnknownNormError(
            f"{true}: a _true norm is evaluated to a stated accuracy by fem.norms.true "
            "(true_norm, or evaluate_named_norms for a mixed list), not under the conventions"
        )
    reductions = {name: _reduction(name) for name in names}
    cell = [n for n, (kind, _) in reductions.items() if kind != "boundary"]
    boundary = [n for n, (kind, _) in reductions.items() if kind == "boundary"]
    out: dict[str, float] = {}
    if boundary:
        out.update(compute_norms(error_field(problem, mesh, u_h, conventions, norms=boundary), boundary))
    acc: dict[str, list[float]] = {name: [] for name in cell}  # the value on each chunk
    n_el = mesh.t.shape[1]
    for start in range(0, n_el if cell else 0, chunk):
        field = error_field(
            problem, mesh, u_h, conventions, norms=cell, elements=np.arange(start, min(n_el, start + chunk))
        )
        for name, value in compute_norms(field, cell).items():
            acc[name].append(value)
        del field  # before the next chunk's is built: one chunk's arrays at a time
    for name in cell:
        kind, p = reductions[name]
        values = np.array(acc[name])
        out[name] = float(values.max()) if kind == "max" else scaled_p_sum([values], p)
    return {name: out[name] for name in names}
