"""Friedrichs–Keller triangulations of the unit square.

Convention (the one source of truth for the mesh width): ``N`` cells per side,
``h = 1/N``, ``(N + 1)²`` vertices, ``2 N²`` right triangles.  Each square cell is
cut by its ``/`` diagonal (south-west to north-east, ``"sw_ne"``) or its ``\\``
diagonal (north-west to south-east, ``"nw_se"``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from skfem import MeshTri

DIAGONALS = ("sw_ne", "nw_se")
DEFAULT_DIAGONAL = DIAGONALS[0]  # the paper's (the README's conventions)


class Triangles(NamedTuple):
    """A mesh as its vertices ``p`` (2, n) and triangles ``t`` (3, m), the arrays of scikit-fem's
    ``MeshTri`` and all that the norms read of one (a ``MeshTri`` serves as well): a job that only
    evaluates norms then does not import scikit-fem, whose import is most of such a job's time."""

    p: np.ndarray
    t: np.ndarray


def mesh_width(N: int) -> float:
    """h = 1/N, the leg length of every triangle."""
    return 1.0 / N


def friedrichs_keller(N: int, diagonal: str = DEFAULT_DIAGONAL, jitter: float = 0.0, seed: int = 0) -> MeshTri:
    """Friedrichs–Keller mesh with ``N`` cells per side.

    ``jitter`` moves interior vertices by up to ``jitter * h`` in each coordinate
    (uniformly at random, reproducible through ``seed``); the mesh stays
    quasi-uniform for ``jitter < 0.5``.
    """
    from skfem import MeshTri  # here: the workflow's config checks import this module for its constants

    _check_fk(N, diagonal)
    if not 0.0 <= jitter < 0.5:
        raise ValueError(f"jitter={jitter} must lie in [0, 0.5)")
    N = int(N)
    p, t = fk_triangles(N, diagonal)
    if jitter > 0.0:
        rng = np.random.default_rng(seed)
        interior = (p[0] > 0) & (p[0] < 1) & (p[1] > 0) & (p[1] < 1)
        p[:, interior] += jitter / N * rng.uniform(-1.0, 1.0, size=(2, interior.sum()))
    return MeshTri(p, t, sort_t=False)


def fk_triangles(N: int, diagonal: str = DEFAULT_DIAGONAL) -> Triangles:
    """The arrays of ``friedrichs_keller(N, diagonal)`` (without jitter), without scikit-fem."""
    _check_fk(N, diagonal)
    return Triangles(fk_vertices(int(N)), _fk_triangles(int(N), diagonal))


def _check_fk(N: int, diagonal: str) -> None:
    if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
        raise ValueError(f"N={N!r} must be a positive integer (cells per side)")
    if diagonal not in DIAGONALS:
        raise ValueError(f"unknown diagonal {diagonal!r}; choose one of {DIAGONALS}")


def fk_vertices(N: int) -> np.ndarray:
    """(2, (N + 1)²): the vertices of the Friedrichs–Keller mesh with ``N`` cells per side (either
    diagonal), vertex (i, j) at (i/N, j/N) with index i (N + 1) + j."""
    t1 = np.linspace(0.0, 1.0, N + 1)
    p = np.empty((2, (N + 1) ** 2))
    p[0].reshape(N + 1, N + 1)[:] = t1[:, None]
    p[1].reshape(N + 1, N + 1)[:] = t1[None, :]
    return p


def _fk_triangles(N: int, diagonal: str) -> np.ndarray:
    """(3, 2 N²) int32: the triangles of the cells (a, b) in order a N + b, first the triangle below
    the diagonal of every cell, then the one above, each with its vertices in ascending order (as
    scikit-fem's ``sort_t`` leaves them): written directly, without the sort."""
    sw = (np.arange(N, dtype=np.int32)[:, None] * np.int32(N + 1) + np.arange(N, dtype=np.int32)[None, :]).ravel()
    up, n = np.int32(N + 1), N * N  # the vertex index of the next grid line in x
    t = np.empty((3, 2 * n), dtype=np.int32)
    if diagonal == "sw_ne":  # (sw, se, ne) and (sw, nw, ne)
        corners = ((0, up, up + 1), (0, 1, up + 1))
    else:  # (sw, nw, se) and (nw, se, ne)
        corners = ((0, 1, up), (1, up, up + 1))
    for kind, offsets in enumerate(corners):
        for row, offset in enumerate(offsets):
            np.add(sw, offset, out=t[row, kind * n : (kind + 1) * n])
    return t


def boundary_edges(mesh: MeshTri) -> np.ndarray:
    """(2, k) the edges on ∂Ω of a triangulation of the unit square, as scikit-fem's
    ``mesh.facets[:, mesh.boundary_facets()]`` gives them (each ``a < b``, in lexicographic order),
    without building every edge of the mesh: an edge on ∂Ω has both vertices on one side of the
    square, and of those edges the ones of a single triangle are on ∂Ω (an interior edge between
    two sides, like a diagonal cutting a corner, belongs to two).  scikit-fem finds all ``3 N²``
    edges first (docs/evidence/design-measurements.md#boundary-edges)."""
    p, t = mesh.p, mesh.t
    x, y = p
    side = (x == 0.0) * np.uint8(1) | (x == 1.0) * np.uint8(2) | (y == 0.0) * np.uint8(4) | (y == 1.0) * np.uint8(8)
    t = t[:, np.count_nonzero(side[t], axis=0) >= 2]  # the triangles with an edge on ∂Ω, and a few more
    edges = np.hstack([t[[0, 1]], t[[1, 2]], t[[0, 2]]])
    edges = edges[:, (side[edges[0]] & side[edges[1]]) != 0]
    edges = np.sort(edges, axis=0)
    keys, counts = np.unique(edges[0].astype(np.int64) * p.shape[1] + edges[1], return_counts=True)
    once = keys[counts == 1]
    return np.vstack(np.divmod(once, p.shape[1])).astype(t.dtype)


def boundary_nodes(mesh: MeshTri) -> np.ndarray:
    """Sorted indices of the vertices on ∂Ω (the constrained unknowns): scikit-fem's
    ``mesh.boundary_nodes()``, from ``boundary_edges``."""
    return np.unique(boundary_edges(mesh))


def fk_boundary_nodes(N: int) -> np.ndarray:
    """``boundary_nodes(friedrichs_keller(N, ...))`` from the vertex numbering alone: vertex (i, j)
    (index i (N + 1) + j) lies on ∂Ω iff i or j is 0 or N.  scikit-fem finds them through the
    mesh's facets (docs/evidence/design-measurements.md#boundary-edges).  The index type
    is scikit-fem's (``int32``, that of ``MeshTri.t``)."""
    i, j = np.divmod(np.arange((N + 1) ** 2, dtype=np.int32), np.int32(N + 1))
    return np.flatnonzero((i == 0) | (i == N) | (j == 0) | (j == N)).astype(np.int32)


def triangles_meeting_disc(p: np.ndarray, t: np.ndarray, support: tuple[np.ndarray, float]) -> np.ndarray:
    """Which triangles ``t`` may have a point in the open disc ``support`` (centre, radius): those
    whose bounding box comes nearer to the centre than the radius (with a margin of round-off).
    A point of the triangle lies in its box, so a triangle left out has none in the disc; the
    empty disc (radius 0: a vanishing ``u``) meets none."""
    centre, radius = support
    if radius <= 0.0:
        return np.zeros(t.shape[1], dtype=bool)
    gaps = []
    for k in range(2):  # the distance from the centre to the box, per coordinate
        a, b, c = p[k][t[0]], p[k][t[1]], p[k][t[2]]
        lo, hi = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
        gaps.append(np.maximum(np.maximum(lo - centre[k], centre[k] - hi), 0.0))
    return np.hypot(gaps[0], gaps[1]) < radius * (1.0 + 1e-12) + 1e-12
