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
``H12``    ``H^{1/2}(∂Ω)`` estimate by interpolation, ``Conventions.h12_form``
``L4plus`` / ``L4minus``  ``‖(u - u_h)^±‖_{L⁴}``; any ``Lp`` works with the suffixes
=========  =====================================================================
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass

import numpy as np
from skfem import CellBasis, ElementTriP1, MeshTri

from signorini.problem import Problem
from signorini.quadrature import dunavant8, gauss_legendre_01, stroud_conical

QUADRATURES = ("dunavant8", "stroud4_right", "stroud4_acute1", "stroud4_acute2")
W1P_FORMS = ("components", "gradient", "seminorm")
MAX_POINTS = ("vertices", "midpoints", "quadrature", "all")
H12_FORMS = ("geometric_full", "geometric_semi")
BOUNDARY_POINTS = 8  # Gauss–Legendre points per boundary edge


class UnknownNormError(ValueError):
    """A norm name that the registry does not know."""


@dataclass(frozen=True)
class Conventions:
    """The choices the paper leaves open (see the README for the evidence behind the defaults)."""

    quadrature: str = "stroud4_acute1"
    w1p_form: str = "components"
    linf_points: str = "all"
    w1inf_points: str = "quadrature"
    h12_form: str = "geometric_full"

    def __post_init__(self) -> None:
        for name, allowed in (
            ("quadrature", QUADRATURES),
            ("w1p_form", W1P_FORMS),
            ("linf_points", MAX_POINTS),
            ("w1inf_points", MAX_POINTS),
            ("h12_form", H12_FORMS),
        ):
            if getattr(self, name) not in allowed:
                raise ValueError(f"unknown convention {name}={getattr(self, name)!r}; choose one of {allowed}")

    def as_dict(self) -> dict[str, str]:
        return asdict(self)


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


def _rolled_mesh(mesh: MeshTri, role: int) -> MeshTri:
    """The same mesh with each triangle's vertices rotated so that local vertex 0 is the
    right-angle vertex (role 0) or the next (role 1) / second-next (role 2) counter-clockwise."""
    p, t = mesh.p, mesh.t
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
    rolled = np.vstack([tt[(start + k) % 3, cols] for k in range(3)])
    return MeshTri(p, rolled, sort_t=False)


def _element_points(mesh: MeshTri, which: str) -> np.ndarray:
    """Reference coordinates of the per-triangle max points: vertices and/or edge midpoints."""
    verts = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    mids = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5]])
    return {"vertices": verts, "midpoints": mids}.get(which, np.hstack([verts, mids]))


def _boundary_edges(mesh: MeshTri) -> tuple[np.ndarray, np.ndarray]:
    """Boundary edges as (start vertex, end vertex) index arrays."""
    facets = mesh.facets[:, mesh.boundary_facets()]
    return facets[0], facets[1]


def _parts_needed(names: list[str] | None) -> set[str]:
    """Which evaluations the named norms need: quadrature, linf, w1inf, boundary."""
    if names is None:
        return {"quadrature", "linf", "w1inf", "boundary"}
    parts = set()
    for name in names:
        parse_norm(name)  # reject unknown names before any work
        if name in ("H12", "L2boundary"):
            parts.add("boundary")
        elif name.startswith("W1inf"):
            parts.add("w1inf")
        elif name.startswith("Linf"):
            parts.add("linf")
        else:
            parts.add("quadrature")
    return parts


def error_field(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    conventions: Conventions | None = None,
    norms: list[str] | None = None,
) -> ErrorField:
    """Evaluate ``e = u - u_h`` and ``∇e`` where the norms need them.

    With ``norms`` given, only the evaluations those norms need are made (the
    others are left ``None``), so one norm can be computed on its own cheaply.
    """
    conv = conventions or Conventions()
    parts = _parts_needed(norms)
    cache: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def at_quadrature() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if "quadrature" not in cache:
            X, W, role = _reference_rule(conv.quadrature)
            qmesh = mesh if role is None else _rolled_mesh(mesh, role)
            basis = CellBasis(qmesh, ElementTriP1(), quadrature=(X, W))
            uh = basis.interpolate(u_h)
            x = np.asarray(basis.global_coordinates())
            cache["quadrature"] = (problem.u(x) - np.asarray(uh), problem.grad_u(x) - uh.grad)
            cache["dx"] = basis.dx
        return (*cache["quadrature"], cache["dx"])

    def at_points(which: str) -> tuple[np.ndarray, np.ndarray]:
        if which == "quadrature":
            return at_quadrature()[:2]
        if which not in cache:
            pts = _element_points(mesh, which)
            mbasis = CellBasis(mesh, ElementTriP1(), quadrature=(pts, np.ones(pts.shape[1])))
            muh = mbasis.interpolate(u_h)
            mx = np.asarray(mbasis.global_coordinates())
            pe, pde = problem.u(mx) - np.asarray(muh), problem.grad_u(mx) - muh.grad
            if which == "all":
                e, de, _ = at_quadrature()
                pe, pde = np.concatenate([pe, e], axis=-1), np.concatenate([pde, de], axis=-1)
            cache[which] = (pe, pde)
        return cache[which]

    e = de = dx = e_max = de_max = e_w1 = eb = dteb = dsb = None
    if "quadrature" in parts:
        e, de, dx = at_quadrature()
    if "linf" in parts:
        e_max = at_points(conv.linf_points)[0]
    if "w1inf" in parts:
        e_w1, de_max = at_points(conv.w1inf_points)
    if "boundary" in parts:
        # Gauss–Legendre on every boundary edge; u_h is linear along each edge
        a, b = _boundary_edges(mesh)
        s, ws = gauss_legendre_01(BOUNDARY_POINTS)
        pa, pb = mesh.p[:, a], mesh.p[:, b]
        length = np.linalg.norm(pb - pa, axis=0)
        tangent = (pb - pa) / length
        xb = pa[:, :, None] + (pb - pa)[:, :, None] * s[None, None, :]
        uhb = u_h[a][:, None] * (1.0 - s) + u_h[b][:, None] * s
        duh_t = ((u_h[b] - u_h[a]) / length)[:, None]
        eb = problem.u(xb) - uhb
        dteb = np.einsum("ie,iek->ek", tangent, problem.grad_u(xb)) - duh_t
        dsb = length[:, None] * ws[None, :]
    return ErrorField(e, de, dx, e_max, de_max, e_w1, eb, dteb, dsb, conv)


# --- the norms ---------------------------------------------------------------------


def lp_norm(f: ErrorField, p: float, part: str = "") -> float:
    """(∫ |g|^p)^{1/p} with g = e, e⁺ = max(e, 0) (part "plus") or e⁻ = max(-e, 0) ("minus")."""
    g = {"": np.abs(f.e), "plus": np.maximum(f.e, 0.0), "minus": np.maximum(-f.e, 0.0)}[part]
    return float(np.sum(g**p * f.dx) ** (1.0 / p))


def linf_norm(f: ErrorField, part: str = "") -> float:
    """max |e| over the max-point set."""
    g = {"": np.abs(f.e_max), "plus": np.maximum(f.e_max, 0.0), "minus": np.maximum(-f.e_max, 0.0)}[part]
    return float(g.max())


def w1p_norm(f: ErrorField, p: float) -> float:
    """W^{1,p}: components (‖e‖ᵖ + ‖∂₁e‖ᵖ + ‖∂₂e‖ᵖ)^{1/p}, gradient (‖e‖ᵖ + ‖|∇e|‖ᵖ)^{1/p}, or seminorm ‖|∇e|‖_p."""
    form = f.conventions.w1p_form
    ae = np.abs(f.e) ** p
    if form == "components":
        integrand = ae + np.abs(f.de[0]) ** p + np.abs(f.de[1]) ** p
    elif form == "gradient":
        integrand = ae + np.hypot(f.de[0], f.de[1]) ** p
    else:
        integrand = np.hypot(f.de[0], f.de[1]) ** p
    return float(np.sum(integrand * f.dx) ** (1.0 / p))


def w1inf_norm(f: ErrorField) -> float:
    """W^{1,∞}: max(|e|, |∂₁e|, |∂₂e|) (components), max(|e|, |∇e|) (gradient) or max |∇e| (seminorm)."""
    form = f.conventions.w1p_form
    if form == "components":
        return float(max(np.abs(f.e_w1).max(), np.abs(f.de_max).max()))
    grad = np.hypot(f.de_max[0], f.de_max[1]).max()
    return float(grad if form == "seminorm" else max(grad, np.abs(f.e_w1).max()))


def h1_norm(f: ErrorField) -> float:
    """(‖e‖²_{L²} + ‖∇e‖²_{L²})^{1/2}."""
    return float(np.sqrt(np.sum((f.e**2 + f.de[0] ** 2 + f.de[1] ** 2) * f.dx)))


def boundary_l2_norm(f: ErrorField) -> float:
    """‖e‖_{L²(∂Ω)}."""
    return float(np.sqrt(np.sum(f.eb**2 * f.dsb)))


def boundary_h1_seminorm(f: ErrorField) -> float:
    """|e|_{H¹(∂Ω)} = ‖∂_t e‖_{L²(∂Ω)}, edge by edge."""
    return float(np.sqrt(np.sum(f.dteb**2 * f.dsb)))


def h12_interpolation_norm(f: ErrorField) -> float:
    """H^{1/2}(∂Ω) estimate ‖e‖_{1/2} ≤ ‖e‖_{L²(∂Ω)}^{1/2} ‖e‖_{H¹(∂Ω)}^{1/2} (H^{1/2} = [L², H¹]_{1/2});
    with the full H¹(∂Ω) norm (``geometric_full``) or the seminorm (``geometric_semi``)."""
    l2, semi = boundary_l2_norm(f), boundary_h1_seminorm(f)
    h1 = np.hypot(l2, semi) if f.conventions.h12_form == "geometric_full" else semi
    return float(np.sqrt(l2 * h1))


_PATTERN = re.compile(r"^(?:(?P<L>L)|(?P<W>W1))(?P<p>inf|\d+(?:\.\d+)?)(?P<part>plus|minus)?$")


def parse_norm(name: str):
    """Map a norm name to a function of an ``ErrorField``; raises ``UnknownNormError``."""
    if name == "H12":
        return h12_interpolation_norm
    if name == "H1":
        return h1_norm
    if name == "L2boundary":
        return boundary_l2_norm
    m = _PATTERN.match(name)
    if m is None or (m["W"] and m["part"]):
        raise UnknownNormError(
            f"unknown norm {name!r}; use Lp, Linf, W1p, W1inf (p ≥ 1), H1, H12, L2boundary, or Lp/Linf with plus/minus"
        )
    part = m["part"] or ""
    if m["p"] == "inf":
        return (lambda f: linf_norm(f, part)) if m["L"] else w1inf_norm
    p = float(m["p"])
    if p < 1.0:
        raise UnknownNormError(f"norm {name!r}: need p ≥ 1")
    return (lambda f: lp_norm(f, p, part)) if m["L"] else (lambda f: w1p_norm(f, p))


def compute_norms(field: ErrorField, names: list[str]) -> dict[str, float]:
    """The requested norms of one error field, by name."""
    funcs = {name: parse_norm(name) for name in names}  # validate all names first
    return {name: fn(field) for name, fn in funcs.items()}
