"""Stage ``free_point_error``: the error ``e = u − u_h`` near the free point ``(x0, 0)`` on one mesh,
and where the maxima over the paper's finite point sets miss the supremum.

The paper's ``L^∞`` and ``W^{1,∞}`` columns are maxima over finite point sets
(``fem.norms.conventions.Conventions``: ``linf_points``, ``w1inf_points``) of ``|e|`` and of the
``W^{1,∞}`` function of the form ``w1p_form`` (``components``: the largest of ``|e|``, ``|∂₁e|``,
``|∂₂e|``).  This module evaluates those functions

- on the conventions' point set of every triangle (vertices, edge midpoints, the points of the
  triangle rule ``Conventions.quadrature``), placed as ``fem.norms.conventional`` places them, so
  that the largest value is the convention's norm, bit for bit;
- on a fine barycentric lattice of every triangle (``SAMPLE`` subdivisions per edge), refined to
  ``REFINE`` subdivisions on the ``CANDIDATES`` triangles of the largest samples: the sampled
  maximum and its location;
- as the ``<name>_true`` norm (``fem.norms.true``: a branch and bound, its value with a bound of
  its error): the supremum over Ω;

and draws heat maps of the function over windows a few mesh widths wide: around the free point,
around the sampled maximum where that lies outside it, and a zoom into the sampled maximum where
the point-set maximum misses the supremum.  ``u_h`` is the P1 function of each
triangle (``fem.norms.conventional.p1_at_points``), ``u`` and ``∇u`` the problem's.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.derivatives import u_and_grad_u
from signorini.fem.norms.conventional import p1_at_points
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.families import define, magnitude
from signorini.plotting import new_figure, save, styled

if TYPE_CHECKING:  # scikit-fem and matplotlib are imported where they are used
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from skfem import MeshTri

    from signorini.fem.problem import Problem
    from signorini.studies.scene.store import SceneMesh

SAMPLE = 16  # lattice subdivisions per triangle edge, every triangle
REFINE = 128  # lattice subdivisions per edge on the candidate triangles
CANDIDATES = 8  # triangles of the largest samples, refined
HEAT = 24  # subdivisions per edge of the heat maps' sub-triangles
WINDOW = (3.0, 1.5)  # a window's half-width and half-height in mesh widths (near the free point: height 3)
ZOOM = 0.25  # the zoomed window: this fraction of WINDOW
MAX_NORMS = ("Linf", "W1inf")
NORM_TITLES = {"Linf": r"$|e|$ ($L^\infty$)", "W1inf": r"$W^{1,\infty}$ function"}
POINT_KINDS = ("vertex", "edge midpoint", "quadrature point")
POINT_MARKERS = {"vertex": ("o", 9), "edge midpoint": ("s", 7), "quadrature point": (".", 3)}

Part = tuple[str, Callable[[np.ndarray, np.ndarray], np.ndarray]]


PART_LABELS = {"e": "|e|", "d1": "|∂₁e|", "d2": "|∂₂e|", "grad": "|∇e|"}  # the parts of the maxima, named


def max_parts(norm: str, form: str) -> list[Part]:
    """The functions of ``(e, ∇e)`` whose largest value the norm ``norm`` (``Linf`` or ``W1inf``) is,
    named: the magnitudes of the norm's parts (``fem.norms.families``): ``|e|``; for ``W^{1,∞}`` in
    the form ``form`` ``|e|``, ``|∂₁e|``, ``|∂₂e|`` (components), ``|e|``, ``|∇e|`` (gradient) or
    ``|∇e|`` (seminorm)."""
    if norm not in MAX_NORMS:
        raise ValueError(f"{norm!r}: the point sets are those of Linf and W1inf")
    parts = define(norm, Conventions(w1p_form=form)).parts
    return [(PART_LABELS[name], lambda e, de, name=name: magnitude(name, e, de)) for name in parts]


def max_function(parts: Sequence[Part], e: np.ndarray, de: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The largest of the parts at each point, and the index of the part that gives it."""
    values = np.stack([f(e, de) for _, f in parts])
    return values.max(axis=0), values.argmax(axis=0)


@dataclass(frozen=True)
class Points:
    """Points ``x`` (2, n), ``e`` (n,) and ``∇e`` (2, n) there, and each point's kind."""

    x: np.ndarray
    e: np.ndarray
    de: np.ndarray
    kind: np.ndarray

    def inside(self, box: tuple[float, float, float, float]) -> Points:
        """The points in the box ``(x_lo, x_hi, y_lo, y_hi)``."""
        keep = (self.x[0] >= box[0]) & (self.x[0] <= box[1]) & (self.x[1] >= box[2]) & (self.x[1] <= box[3])
        return Points(self.x[:, keep], self.e[keep], self.de[:, keep], self.kind[keep])


def errors_at(problem: Problem, mesh: MeshTri, u_h: np.ndarray, X: np.ndarray, t: np.ndarray | None = None) -> Points:
    """``e`` and ``∇e`` at the reference points ``X`` (2, q) of the triangles ``t`` (default: all),
    flattened triangle by triangle (kind ``"sample"``)."""
    x, uh, duh, _ = p1_at_points(mesh.p, mesh.t if t is None else t, u_h, X)
    u, du = u_and_grad_u(problem, x)
    e, de = u - uh, du - duh
    return Points(x.reshape(2, -1), e.ravel(), de.reshape(2, -1), np.full(e.size, "sample"))


def point_set(problem: Problem, mesh: MeshTri, u_h: np.ndarray, conventions: Conventions, which: str) -> Points:
    """``e`` and ``∇e`` on the conventions' point set ``which`` (``vertices``, ``midpoints``,
    ``quadrature`` or ``all``) of every triangle, placed as ``fem.norms.conventional.error_field``
    places them (the triangle rule of a Stroud rule rotated to its collapsed vertex)."""
    from signorini.fem.norms.conventional import element_points, triangle_rule

    sets = []
    if which in ("vertices", "all"):
        sets.append(("vertex", element_points("vertices"), mesh.t))
    if which in ("midpoints", "all"):
        sets.append(("edge midpoint", element_points("midpoints"), mesh.t))
    if which in ("quadrature", "all"):
        X, _, t = triangle_rule(mesh.p, mesh.t, conventions.quadrature)
        sets.append(("quadrature point", X, t))
    found = [errors_at(problem, mesh, u_h, X, t) for _, X, t in sets]
    kinds = np.concatenate([np.full(f.e.size, kind) for (kind, _, _), f in zip(sets, found, strict=True)])
    return Points(*(np.concatenate([getattr(f, a) for f in found], axis=-1) for a in ("x", "e", "de")), kinds)


@dataclass(frozen=True)
class Maximum:
    """The largest value of a norm's function over some points: where, which part, of which kind."""

    value: float
    point: np.ndarray
    part: str
    kind: str


def largest(points: Points, parts: Sequence[Part]) -> Maximum:
    """The largest value of the parts' maximum over the points (the first where several tie)."""
    values, which = max_function(parts, points.e, points.de)
    k = int(np.argmax(values))
    return Maximum(float(values[k]), points.x[:, k].copy(), parts[int(which[k])][0], str(points.kind[k]))


def lattice(m: int) -> np.ndarray:
    """Reference coordinates (2, q) of the barycentric lattice with ``m`` subdivisions per edge."""
    i, j = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
    keep = i + j <= m
    return np.vstack([i[keep], j[keep]]).astype(float) / m


def sampled_maximum(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    parts: Sequence[Part],
    m: int = SAMPLE,
    fine: int = REFINE,
    top: int = CANDIDATES,
) -> Maximum:
    """The largest value of the parts on the lattice of ``m`` subdivisions of every triangle, then
    on that of ``fine`` subdivisions of the ``top`` triangles of the largest samples (kind
    ``"sample"``)."""
    X, n_el, per = lattice(m), mesh.t.shape[1], np.empty(mesh.t.shape[1])
    for start in range(0, n_el, 1 << 14):
        el = np.arange(start, min(n_el, start + (1 << 14)))
        pts = errors_at(problem, mesh, u_h, X, mesh.t[:, el])
        per[el] = max_function(parts, pts.e, pts.de)[0].reshape(el.size, -1).max(axis=1)
    best = np.argsort(-per, kind="stable")[:top]
    return largest(errors_at(problem, mesh, u_h, lattice(fine), mesh.t[:, best]), parts)


@dataclass(frozen=True)
class MaxNorm:
    """One maximum norm on one mesh: the conventions' point set and its maximum (the convention's
    value), the sampled maximum, and the true norm (its value and the bound of its error)."""

    name: str
    which: str
    parts: tuple
    points: Points
    point_max: Maximum
    sampled: Maximum
    true_value: float
    true_error: float

    @property
    def gap(self) -> float:
        """(point-set maximum − supremum) / supremum."""
        return (self.point_max.value - self.true_value) / self.true_value

    @property
    def attains(self) -> bool:
        """Whether the point-set maximum equals the supremum to the accuracy of the true norm."""
        return abs(self.true_value - self.point_max.value) <= self.true_error


def max_norm(problem: Problem, mesh: MeshTri, u_h: np.ndarray, conventions: Conventions, name: str) -> MaxNorm:
    """``MaxNorm`` of ``Linf`` or ``W1inf`` under the conventions."""
    from signorini.fem.norms.true import true_norm

    which = getattr(conventions, define(name, conventions).points)  # linf_points or w1inf_points
    parts = tuple(max_parts(name, conventions.w1p_form))
    pts = point_set(problem, mesh, u_h, conventions, which)
    true = true_norm(problem, mesh, u_h, f"{name}_true", conventions)
    sampled = sampled_maximum(problem, mesh, u_h, parts)
    return MaxNorm(name, which, parts, pts, largest(pts, parts), sampled, true.value, true.error_estimate)


# --- the windows and their heat maps ------------------------------------------------------------

Box = tuple[float, float, float, float]  # x_lo, x_hi, y_lo, y_hi


def window_around(point: np.ndarray, h: float, scale: float = 1.0) -> Box:
    """The window ``2 WINDOW[0] × 2 WINDOW[1]`` mesh widths (times ``scale``) centred at ``point``,
    moved into the unit square (a point on the bottom edge: the window above it, as high)."""
    half = (scale * WINDOW[0] * h, scale * WINDOW[1] * h)
    box = []
    for c, w in zip(point, half, strict=True):
        lo = min(max(0.0, float(c) - w), 1.0 - 2.0 * w)
        box += [lo, lo + 2.0 * w]
    return box[0], box[1], box[2], box[3]


def in_box(point: np.ndarray, box: Box) -> bool:
    """Whether the point lies in the (closed) box."""
    return bool(box[0] <= point[0] <= box[1] and box[2] <= point[1] <= box[3])


def elements_in(mesh: MeshTri, box: Box) -> np.ndarray:
    """The triangles whose bounding box meets the box."""
    v = mesh.p[:, mesh.t]
    lo, hi = v.min(axis=1), v.max(axis=1)
    return np.flatnonzero((hi[0] >= box[0]) & (lo[0] <= box[1]) & (hi[1] >= box[2]) & (lo[1] <= box[3]))


def sub_triangles(m: int) -> np.ndarray:
    """Reference vertices (2, 3, m²) of the m² triangles of the lattice with ``m`` subdivisions."""
    up = [((i, j), (i + 1, j), (i, j + 1)) for i in range(m) for j in range(m - i)]
    down = [((i + 1, j), (i + 1, j + 1), (i, j + 1)) for i in range(m) for j in range(m - i - 1)]
    return np.array(up + down, dtype=float).transpose(2, 1, 0) / m


@dataclass(frozen=True)
class Panel:
    """What one heat map draws: the norm, the window, its title, the sub-triangles (2, 3, K) and the
    norm's function at their centroids, the mesh's triangles (2, 3, E) meeting the window, the
    free point, and the two maxima it marks: the norm's (``MaxNorm.point_max``, ``sampled``) where
    they lie in the window, else the largest in the window (``local``)."""

    norm: MaxNorm
    box: Box
    title: str
    faces: np.ndarray
    values: np.ndarray
    triangles: np.ndarray
    free_point: np.ndarray
    point_max: Maximum
    sampled: Maximum
    local: bool


def panel(
    problem: Problem, mesh: MeshTri, u_h: np.ndarray, norm: MaxNorm, box: Box, title: str, m: int = HEAT
) -> Panel:
    """The ``Panel`` of a norm over a window: its function on the sub-triangles of the lattice of ``m``
    subdivisions of every triangle meeting the window; where a maximum of the norm lies outside
    the window, the largest in the window (of the point set; of the lattice of ``REFINE``
    subdivisions of those triangles)."""
    el = elements_in(mesh, box)
    sub = sub_triangles(m)
    centroids = errors_at(problem, mesh, u_h, sub.mean(axis=1), mesh.t[:, el])
    values, _ = max_function(norm.parts, centroids.e, centroids.de)
    v = mesh.p[:, mesh.t[:, el]]  # (2, 3, E)
    jac = np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]], axis=1)  # (2, 2, E)
    faces = v[:, 0, :, None, None] + np.einsum("dke,kcs->decs", jac, sub)  # (2, E, 3, K)
    faces = faces.transpose(0, 2, 1, 3).reshape(2, 3, -1)  # triangle by triangle, as the centroids
    point_max, sampled = norm.point_max, norm.sampled
    local = not (in_box(point_max.point, box) and in_box(sampled.point, box))
    if local:
        point_max = largest(norm.points.inside(box), norm.parts)
        sampled = largest(errors_at(problem, mesh, u_h, lattice(REFINE), mesh.t[:, el]).inside(box), norm.parts)
    return Panel(norm, box, title, faces, values, v, problem.singular_points()[:, 0], point_max, sampled, local)


def windows(norm: MaxNorm, free_point: np.ndarray, h: float) -> list[tuple[Box, str, float]]:
    """A norm's windows, their titles and how many times finer their heat maps are sampled: around
    the free point; around the sampled maximum where that lies outside; zoomed into the sampled
    maximum where the point-set maximum misses the supremum (``MaxNorm.attains``)."""
    near = window_around(free_point, h)
    out = [(near, "near the free point", 1.0)]
    if not in_box(norm.sampled.point, near):
        out.append((window_around(norm.sampled.point, h), "around its sampled maximum", 1.0))
    if not norm.attains:
        out.append((window_around(norm.sampled.point, h, ZOOM), "zoomed into its sampled maximum", 1.0 / ZOOM))
    return out


def panels(problem: Problem, mesh: MeshTri, u_h: np.ndarray, norms: Sequence[MaxNorm], h: float) -> list[Panel]:
    """The ``Panel`` of every window (``windows``) of every norm."""
    free = problem.singular_points()[:, 0]
    return [
        panel(problem, mesh, u_h, norm, box, f"{NORM_TITLES[norm.name]} {where}", round(HEAT * scale))
        for norm in norms
        for box, where, scale in windows(norm, free, h)
    ]


# --- the figure -----------------------------------------------------------------------------------

POINT_SETS = {
    "vertices": "the vertices",
    "midpoints": "the edge midpoints",
    "quadrature": "the 16 quadrature points",
    "all": "the vertices, edge midpoints and 16 quadrature points",
}


def _at(m: Maximum) -> str:
    return f"{m.part} at ({m.point[0]:.5f}, {m.point[1]:.5f})"


def summary_lines(data: Panel) -> list[str]:
    """The panel's numbers: the supremum (true norm), the point-set maximum of the norm with the
    verdict on it (``MaxNorm.attains``) and the sampled maximum; where the norm's maxima lie
    outside the window (``Panel.local``), the two largest values in the window and their gap."""
    norm, kind = (
        data.norm,
        {"edge midpoint": "an edge midpoint"}.get(data.norm.point_max.kind, f"a {data.norm.point_max.kind}"),
    )
    verdict = "equals it to the true norm's accuracy"
    if not norm.attains:  # above the supremum beyond its error: the true norm's bound would be wrong
        verdict = f"{'misses' if norm.gap < 0 else 'exceeds'} it by {100.0 * norm.gap:+.2f} %"
    lines = [
        f"supremum over Ω (the true norm): {norm.true_value:.5e}, error ≤ {norm.true_error:.1e}",
        f"largest over {POINT_SETS[norm.which]} per triangle",
        f"(the convention's value): {norm.point_max.value:.5e}, {_at(norm.point_max)}, {kind}:",
        f"it {verdict}",
        f"sampled maximum: {norm.sampled.value:.5e}, {_at(norm.sampled)}",
    ]
    if data.local:
        gap = (data.point_max.value - data.sampled.value) / data.sampled.value
        lines += [
            "both outside this window; the largest in it, marked:",
            f"sampled {data.sampled.value:.5e}, over the point set {data.point_max.value:.5e} ({100.0 * gap:+.2f} %)",
        ]
    return lines


def _scatter_points(ax: Axes, data: Panel) -> None:
    """The point set (vertices, edge midpoints, quadrature points), the two maxima and the free point."""
    pts = data.norm.points.inside(data.box)
    for kind in POINT_KINDS:
        sel = pts.kind == kind
        if sel.any():
            marker, size = POINT_MARKERS[kind]
            face = "black" if kind == "quadrature point" else "none"
            ax.scatter(*pts.x[:, sel], s=size, marker=marker, facecolors=face, edgecolors="black", linewidths=0.7)
    if in_box(data.free_point, data.box):  # hollow and on top: a maximum may sit at the free point
        ax.scatter(
            *data.free_point,
            s=130,
            marker="^",
            facecolors="none",
            edgecolors="orange",
            linewidths=1.8,
            zorder=6,
            clip_on=False,
        )
    for m, marker, color, size in ((data.point_max, "*", "red", 220), (data.sampled, "X", "magenta", 70)):
        if in_box(m.point, data.box):
            ax.scatter(
                *m.point,
                s=size,
                marker=marker,
                color=color,
                edgecolors="white",
                linewidths=0.7,
                zorder=5,
                clip_on=False,
            )


@styled
def free_point_panel(data: Panel, ax: Axes | None = None) -> Axes:
    """The heat map of a ``Panel`` on ``ax``: the norm's function on the sub-triangles (flat per
    sub-triangle: ``∇u_h`` jumps across the mesh's edges), the mesh's edges (white), the point set
    (vertices ○, edge midpoints □, quadrature points ·), the point-set maximum (red star), the
    sampled maximum (magenta cross) and the free point (hollow orange triangle), the numbers below
    (``summary_lines``).  Returns the axes."""
    from matplotlib.collections import PolyCollection
    from matplotlib.tri import Triangulation

    if ax is None:
        ax = new_figure(figsize=(7.0, 5.0)).subplots()
    K = data.faces.shape[2]
    tri = Triangulation(data.faces[0].T.ravel(), data.faces[1].T.ravel(), np.arange(3 * K).reshape(K, 3))
    heat = ax.tripcolor(tri, facecolors=data.values, cmap="viridis", shading="flat", rasterized=True)
    ax.figure.colorbar(heat, ax=ax, fraction=0.04, pad=0.02)
    edges = PolyCollection(data.triangles.transpose(2, 1, 0), facecolor="none", edgecolor="white", linewidth=0.6)
    ax.add_collection(edges)
    _scatter_points(ax, data)
    ax.set_xlim(data.box[0], data.box[1])
    ax.set_ylim(data.box[2], data.box[3])
    ax.set_aspect("equal")
    ax.set_xlabel("$x_1$", labelpad=1)
    ax.set_ylabel("$x_2$")
    ax.set_title(data.title, fontsize=11)
    ax.text(0.0, -0.2, "\n".join(summary_lines(data)), transform=ax.transAxes, va="top", fontsize=8.5)
    return ax


def _legend(fig: Figure) -> None:
    """The markers' legend, below the panels."""
    from matplotlib.lines import Line2D

    def handle(marker, label, **kw):
        return Line2D([], [], linestyle="none", marker=marker, label=label, **kw)

    handles = [
        handle("o", "vertex", markerfacecolor="none", markeredgecolor="black"),
        handle("s", "edge midpoint", markerfacecolor="none", markeredgecolor="black", markersize=5),
        handle(".", "quadrature point", color="black"),
        handle("*", "largest over the point set", color="red", markersize=12),
        handle("X", "sampled maximum", color="magenta", markersize=8),
        handle("^", "free point $(x_0, 0)$", markerfacecolor="none", markeredgecolor="orange", markeredgewidth=1.8),
    ]
    fig.legend(
        handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.975), ncol=len(handles), fontsize=9, frameon=False
    )


@styled
def free_point_figure(data: Sequence[Panel], N: int, columns: int = 2) -> Figure:
    """The ``free_point_panel`` of every panel on a grid of ``columns`` columns, titled by the mesh.
    Returns the figure."""
    rows = -(-len(data) // columns)
    fig = new_figure(figsize=(8.0 * columns, 5.4 * rows + 0.9))
    axes = np.atleast_1d(fig.subplots(rows, columns)).ravel()
    for ax, item in zip(axes, data, strict=False):
        free_point_panel(item, ax=ax)
    for ax in axes[len(data) :]:
        ax.set_visible(False)
    w1 = ", ".join(name for name, _ in data[-1].norm.parts) if data else ""
    fig.suptitle(
        f"The error $e = u - u_h$ on the mesh N = {N} ($h$ = 1/{N}) and the point sets of the paper's maxima "
        f"(their $W^{{1,\\infty}}$ function: the largest of {w1})",
        fontsize=12,
        y=0.995,
    )
    _legend(fig)
    height = fig.get_figheight()
    fig.subplots_adjust(left=0.05, right=0.95, top=1.0 - 1.0 / height, bottom=1.5 / height, hspace=0.7, wspace=0.18)
    return fig


def free_point_stage(at: SceneMesh, solution_path: str | os.PathLike, conventions: Mapping, outputs: Mapping) -> None:
    """Stage ``free_point_error``: ``free_point_figure`` of the mesh ``at`` (a ``SceneMesh``) and its
    solution, under the conventions (the fields of ``Conventions``), saved to ``outputs`` (keys
    ``pdf``, ``png``)."""
    mesh, u_h, problem = at.mesh(), at.load_solution(solution_path), at.problem
    conv = Conventions(**dict(conventions))
    norms = [max_norm(problem, mesh, u_h, conv, name) for name in MAX_NORMS]
    save(free_point_figure(panels(problem, mesh, u_h, norms, at.h), at.N), outputs["pdf"], outputs["png"])
