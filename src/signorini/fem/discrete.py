"""The discrete Signorini problem (S_h) on a Friedrichs–Keller mesh or any other triangulation of
the unit square (``fem.solve`` solves it).

``(u_h, v_h - u_h)_{H¹} ≥ (f, v_h - u_h)`` for all ``v_h ∈ K_h = {v_h ∈ V_h : v_h ≥ 0 on ∂Ω}``;
with P1 elements this is the QP ``min ½ uᵀAu - bᵀu`` s.t. ``u_i ≥ 0`` at boundary nodes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import MeshTri

from signorini.fem.assembly import CHUNK_ELEMENTS, fk_stencil_matrix, load_vector, system_matrix
from signorini.fem.mesh import DEFAULT_DIAGONAL, boundary_nodes, fk_boundary_nodes, fk_vertices, friedrichs_keller
from signorini.fem.problem import Problem


@dataclass
class DiscreteProblem:
    """Mesh, ``A = K + c M``, ``b = ∫ f φ`` and the constrained (boundary) nodes.  ``mesh`` None:
    the Friedrichs–Keller mesh ``friedrichs_keller(N, diagonal)``, not built (a solve needs only
    its ``vertices``; the triangles of N = 4001 are 0.4 GB)."""

    problem: Problem
    N: int
    diagonal: str
    mesh: MeshTri | None
    A: sp.csr_matrix
    b: np.ndarray
    boundary: np.ndarray

    @property
    def vertices(self) -> np.ndarray:
        """(2, n): the mesh's vertices, node k at ``vertices[:, k]``."""
        return fk_vertices(self.N) if self.mesh is None else self.mesh.p


def build(problem: Problem, N: int, diagonal: str = DEFAULT_DIAGONAL, mesh: MeshTri | None = None) -> DiscreteProblem:
    """Mesh and assemble (S_h) for ``N`` cells per side: ``A`` written from the exact stencil of the
    Friedrichs–Keller mesh (``assembly.fk_stencil_matrix``: scikit-fem's matrix without the round-off
    of the mesh's coordinates) and ``b`` streamed over the triangles that meet the support of ``f``
    (bit for bit scikit-fem's), in O(#vertices) memory.  Given another ``mesh`` (a family of
    ``fem.mesh_families`` with parameter ``N``), ``A`` and ``b`` are scikit-fem's assembly on it,
    in chunks of triangles, and the constrained nodes its vertices on ∂Ω."""
    if mesh is not None:
        A, b = system_matrix(mesh, problem.c, chunk=CHUNK_ELEMENTS), load_vector(mesh, problem)
        return DiscreteProblem(problem, int(N), diagonal, mesh, A, b, boundary_nodes(mesh))
    mesh = friedrichs_keller(N, diagonal)
    A, b = fk_stencil_matrix(mesh, int(N), problem.c), load_vector(mesh, problem)
    return DiscreteProblem(problem, int(N), diagonal, mesh, A, b, fk_boundary_nodes(int(N)))


INTERPOLATION_CHUNK = 1 << 18  # points per block of ``interpolate_fk``: its temporaries stay in the cache


def interpolate_fk(N: int, diagonal: str, values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Evaluate the P1 function ``values`` on the (unjittered) Friedrichs–Keller mesh
    ``friedrichs_keller(N, diagonal)`` at ``points`` (shape (2, m)), by direct cell location, a
    block of ``INTERPOLATION_CHUNK`` points at a time."""
    V = np.asarray(values).reshape(N + 1, N + 1)  # vertex (i, j) at (i/N, j/N), see mesh.py
    points = np.asarray(points)
    out = np.empty(points.shape[1])
    for start in range(0, points.shape[1], INTERPOLATION_CHUNK):
        block = slice(start, start + INTERPOLATION_CHUNK)
        out[block] = _interpolate_block(N, diagonal, V, points[0, block], points[1, block])
    return out


def _interpolate_block(N: int, diagonal: str, V: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    xs, ys = np.clip(x * N, 0.0, N), np.clip(y * N, 0.0, N)
    i, j = np.minimum(xs.astype(int), N - 1), np.minimum(ys.astype(int), N - 1)
    xi, eta = xs - i, ys - j
    v00, v10, v01, v11 = V[i, j], V[i + 1, j], V[i, j + 1], V[i + 1, j + 1]
    if diagonal == "sw_ne":
        lower = v00 + xi * (v10 - v00) + eta * (v11 - v10)
        upper = v00 + eta * (v01 - v00) + xi * (v11 - v01)
        return np.where(xi >= eta, lower, upper)
    lower = v00 + xi * (v10 - v00) + eta * (v01 - v00)
    upper = v11 + (1.0 - xi) * (v01 - v11) + (1.0 - eta) * (v10 - v11)
    return np.where(xi + eta <= 1.0, lower, upper)
