"""Families of triangulations of the unit square beyond the paper's Friedrichs–Keller mesh.

Each family is a function of its mesh parameter ``N`` (cells, or points, per side: the mesh size
``h`` is about ``1/N``) and of its own parameters, returning a scikit-fem ``MeshTri`` whose
vertices on ∂Ω have coordinates exactly ``0.0`` or ``1.0`` (``fem.mesh.boundary_edges`` finds its
boundary from them):

=====================  ==========================================================================
``friedrichs_keller``  the paper's mesh (``fem.mesh.friedrichs_keller``): every cell cut by the same
                       diagonal; an even ``N`` puts a vertex at the free point ``(1/2, 0)``
``union_jack``         the cells cut by alternating diagonals (``/`` where ``a + b`` is even, ``\\``
                       where it is odd, for cell ``(a, b)``): every other vertex has eight
                       neighbours, the others four
``graded``             the Friedrichs–Keller mesh refined toward the point ``(x0, 0)`` with the
                       exponent ``grading`` (``1``: none; above 1 the triangles shrink toward the
                       point like ``(distance)^(1 − 1/grading)``), shape kept by red–green–blue
                       refinement
``delaunay``           the Delaunay triangulation (``scipy.spatial.Delaunay``) of ``N + 1`` equally
                       spaced points per side and a triangular lattice of spacing ``1/N`` inside,
                       each interior point moved at random by up to ``jitter / N`` (``seed``):
                       unstructured and quasi-uniform, no symmetry left
=====================  ==========================================================================

``mesh_size`` is the ``h`` the rates are measured against (the longest edge); ``min_angle`` the
quality of a mesh (its smallest angle).  A scene names its family and the family's parameters
(``mesh: {family: delaunay, seed: 1}``); ``check_mesh_spec`` checks them against the family's
function, so a new family is one function here and its name in the configuration schema.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from signorini.fem.mesh import DEFAULT_DIAGONAL, friedrichs_keller

if TYPE_CHECKING:
    from skfem import MeshTri


def _tensor_mesh(xs: np.ndarray, ys: np.ndarray, slash: np.ndarray) -> MeshTri:
    """The tensor grid of the lines ``xs`` and ``ys``, vertex ``(i, j)`` numbered ``i len(ys) + j``,
    cell ``(a, b)`` cut by its ``/`` diagonal where ``slash[a, b]``, else by its ``\\`` one."""
    from skfem import MeshTri

    nx, ny = xs.size, ys.size
    p = np.vstack([np.repeat(xs, ny), np.tile(ys, nx)])
    a, b = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), indexing="ij")
    sw = (a * ny + b).ravel()
    se, nw, ne = sw + ny, sw + 1, sw + ny + 1
    s = slash.ravel()
    first = np.where(s, np.vstack([sw, se, ne]), np.vstack([sw, se, nw]))
    second = np.where(s, np.vstack([sw, ne, nw]), np.vstack([se, ne, nw]))
    return MeshTri(p, np.hstack([first, second]).astype(np.int32))


def union_jack(N: int) -> MeshTri:
    """``N × N`` cells cut by alternating diagonals (the module's table)."""
    lines = np.linspace(0.0, 1.0, N + 1)
    a, b = np.meshgrid(np.arange(N), np.arange(N), indexing="ij")
    return _tensor_mesh(lines, lines, (a + b) % 2 == 0)


def graded(N: int, grading: float = 2.0, x0: float = 0.5) -> MeshTri:
    """The Friedrichs–Keller mesh of ``N`` cells per side refined toward ``(x0, 0)`` (the module's
    table) by scikit-fem's adaptive red–green–blue refinement, which keeps the triangles' shape:
    a triangle is refined while its longest edge exceeds ``h (r / R)^(1 − 1/grading)``, ``r`` the
    distance of its centroid from the point, ``R = 1`` and ``r`` not below ``h^grading``."""
    if not grading >= 1.0:
        raise ValueError(f"grading={grading} must be at least 1 (1: no refinement)")
    if not 0.0 < x0 < 1.0:
        raise ValueError(f"x0={x0} must lie inside (0, 1)")
    h = 1.0 / N
    mesh = friedrichs_keller(N)
    while True:
        longest, centroid = longest_edges(mesh), mesh.p[:, mesh.t].mean(axis=1)
        r = np.maximum(np.hypot(centroid[0] - x0, centroid[1]), h**grading)
        marked = np.flatnonzero(longest > np.sqrt(2.0) * h * r ** (1.0 - 1.0 / grading) * (1.0 + 1e-12))
        if not marked.size:
            return mesh
        mesh = mesh.refined(marked)


def delaunay(N: int, jitter: float = 0.25, seed: int = 0) -> MeshTri:
    """The Delaunay triangulation of the module's table: boundary points equally spaced, interior
    points on a triangular lattice moved at random by up to ``jitter / N``."""
    from scipy.spatial import Delaunay
    from skfem import MeshTri

    if not 0.0 <= jitter < 0.5:
        raise ValueError(f"jitter={jitter} must lie in [0, 0.5)")
    h = 1.0 / N
    side = np.linspace(0.0, 1.0, N + 1)
    boundary = np.hstack([
        np.vstack([side[:-1], np.zeros(N)]), np.vstack([np.ones(N), side[:-1]]),
        np.vstack([side[:0:-1], np.ones(N)]), np.vstack([np.zeros(N), side[:0:-1]]),
    ])
    dy = h * np.sqrt(3.0) / 2.0
    rows = np.arange(1, int(np.floor((1.0 - 0.5 * dy) / dy)) + 1)
    xs, ys = [], []
    for r in rows:
        x = np.arange(h * (1.0 if r % 2 else 0.5), 1.0 - 0.5 * h, h)
        xs.append(x)
        ys.append(np.full(x.size, r * dy))
    interior = np.vstack([np.concatenate(xs), np.concatenate(ys)])
    interior = interior[:, (interior[1] < 1.0 - 0.5 * dy) & (interior[0] > 0.4 * h) & (interior[0] < 1.0 - 0.4 * h)]
    rng = np.random.default_rng(seed)
    interior = interior + jitter * h * rng.uniform(-1.0, 1.0, interior.shape)
    p = np.hstack([boundary, interior])
    t = Delaunay(p.T).simplices.T
    v = p[:, t]
    area = (v[0, 1] - v[0, 0]) * (v[1, 2] - v[1, 0]) - (v[0, 2] - v[0, 0]) * (v[1, 1] - v[1, 0])
    return MeshTri(p, np.ascontiguousarray(t[:, np.abs(area) > 1e-14 * h * h], dtype=np.int32))


def longest_edges(mesh: MeshTri) -> np.ndarray:
    """The longest edge of each triangle."""
    v = mesh.p[:, mesh.t]
    return np.max([np.hypot(*(v[:, k] - v[:, (k + 1) % 3])) for k in range(3)], axis=0)


def mesh_size(mesh: MeshTri) -> float:
    """``h``: the longest edge of the mesh."""
    return float(longest_edges(mesh).max())


def min_angle(mesh: MeshTri) -> float:
    """The smallest angle of the mesh's triangles, in degrees."""
    v = mesh.p[:, mesh.t]
    smallest = np.inf
    for k in range(3):
        a, b = v[:, (k + 1) % 3] - v[:, k], v[:, (k + 2) % 3] - v[:, k]
        cos = np.sum(a * b, axis=0) / (np.hypot(*a) * np.hypot(*b))
        smallest = min(smallest, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).min()))
    return smallest


MESH_FAMILIES: dict[str, Callable[..., MeshTri]] = {
    "friedrichs_keller": friedrichs_keller,
    "union_jack": union_jack,
    "graded": graded,
    "delaunay": delaunay,
}


FRIEDRICHS_KELLER = "friedrichs_keller"  # the paper's family, every scene's unless it says otherwise


def family_parameters(family: str) -> dict[str, Any]:
    """{parameter: default} of a family's function beyond ``N`` (``friedrichs_keller``'s diagonal,
    jitter and seed included)."""
    if family not in MESH_FAMILIES:
        raise ValueError(f"unknown mesh family {family!r}; choose one of {sorted(MESH_FAMILIES)}")
    parameters = list(inspect.signature(MESH_FAMILIES[family]).parameters.values())[1:]
    return {par.name: par.default for par in parameters}


def check_mesh_spec(spec: Mapping[str, Any]) -> tuple[str, dict[str, Any]]:
    """``(family, params)`` of a scene's ``mesh`` block, each parameter one the family's function
    takes, of its default's type (an integer where it is a float); a ``ValueError`` naming the
    parameter otherwise.  The Friedrichs–Keller diagonal is the scene's own ``diagonal``, not a
    parameter here."""
    params = dict(spec)
    family = params.pop("family", FRIEDRICHS_KELLER)
    known = family_parameters(family)
    if family == FRIEDRICHS_KELLER:
        known.pop("diagonal")
    for name, value in params.items():
        if name not in known:
            raise ValueError(f"mesh family {family!r} has no parameter {name!r}; its parameters: {sorted(known)}")
        default = known[name]
        kinds = (int, float) if isinstance(default, float) else (type(default),)
        if isinstance(value, bool) or not isinstance(value, kinds):
            raise ValueError(f"mesh parameter {name}={value!r} must be a {type(default).__name__}, like its default")
    return family, params


def paper_mesh(spec: Mapping[str, Any]) -> bool:
    """Whether a scene's ``mesh`` block names the paper's Friedrichs–Keller mesh (the family
    without parameters: two integers define it, no artifact is needed)."""
    family, params = check_mesh_spec(spec)
    return family == FRIEDRICHS_KELLER and not params


def build_mesh(family: str, N: int, **params) -> MeshTri:
    """The mesh of ``family`` (``MESH_FAMILIES``) with parameter ``N`` and the family's ``params``."""
    if family not in MESH_FAMILIES:
        raise ValueError(f"unknown mesh family {family!r}; choose one of {sorted(MESH_FAMILIES)}")
    return MESH_FAMILIES[family](N, **params)


def mesh_from_spec(N: int, spec: Mapping[str, Any], diagonal: str = DEFAULT_DIAGONAL) -> MeshTri:
    """The mesh a ``mesh`` block (a scene's, an atlas case's) defines at ``N``: the paper's
    Friedrichs–Keller mesh with ``diagonal`` for an empty block, else its family with its
    parameters (a Friedrichs–Keller family with ``diagonal``)."""
    family, params = check_mesh_spec(spec)
    if family == FRIEDRICHS_KELLER:
        params["diagonal"] = diagonal
    return build_mesh(family, N, **params)


def describe_mesh(mesh: MeshTri, points: Sequence[tuple[float, float]] = ()) -> dict[str, Any]:
    """What a reader of a mesh wants to know of it: vertices, triangles, the longest and shortest
    edge, the smallest diameter of a triangle (its longest edge), the smallest angle, and whether
    each of ``points`` (a problem's singular points, the free point) is a vertex
    (``points_are_vertices``)."""
    v = mesh.p[:, mesh.t]
    edges = np.array([np.hypot(*(v[:, k] - v[:, (k + 1) % 3])) for k in range(3)])
    info = {
        "n_vertices": int(mesh.p.shape[1]),
        "n_triangles": int(mesh.t.shape[1]),
        "longest_edge": float(edges.max()),
        "shortest_edge": float(edges.min()),
        "smallest_diameter": float(edges.max(axis=0).min()),
        "min_angle_deg": min_angle(mesh),
    }
    if len(points):
        info["points_are_vertices"] = [bool(np.hypot(mesh.p[0] - x, mesh.p[1] - y).min() <= 1e-12) for x, y in points]
    return info
