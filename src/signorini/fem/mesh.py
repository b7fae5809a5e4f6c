"""Friedrichs–Keller triangulations of the unit square.

Convention (the one source of truth for the mesh width): ``N`` cells per side,
``h = 1/N``, ``(N + 1)²`` vertices, ``2 N²`` right triangles.  Each square cell is
cut by its ``/`` diagonal (south-west to north-east, ``"sw_ne"``) or its ``\\``
diagonal (north-west to south-east, ``"nw_se"``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from skfem import MeshTri

DIAGONALS = ("sw_ne", "nw_se")
DEFAULT_DIAGONAL = DIAGONALS[0]  # the paper's (the README's conventions)


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

    if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
        raise ValueError(f"N={N!r} must be a positive integer (cells per side)")
    if diagonal not in DIAGONALS:
        raise ValueError(f"unknown diagonal {diagonal!r}; choose one of {DIAGONALS}")
    if not 0.0 <= jitter < 0.5:
        raise ValueError(f"jitter={jitter} must lie in [0, 0.5)")
    N = int(N)
    t1 = np.linspace(0.0, 1.0, N + 1)
    X, Y = np.meshgrid(t1, t1, indexing="ij")  # vertex (i, j) has index i (N + 1) + j
    p = np.vstack([X.ravel(), Y.ravel()])
    idx = np.arange((N + 1) ** 2).reshape(N + 1, N + 1)
    sw, se = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    nw, ne = idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    if diagonal == "sw_ne":
        t = np.hstack([np.vstack([sw, se, ne]), np.vstack([sw, ne, nw])])
    else:
        t = np.hstack([np.vstack([sw, se, nw]), np.vstack([se, ne, nw])])
    if jitter > 0.0:
        rng = np.random.default_rng(seed)
        interior = (p[0] > 0) & (p[0] < 1) & (p[1] > 0) & (p[1] < 1)
        p[:, interior] += jitter / N * rng.uniform(-1.0, 1.0, size=(2, interior.sum()))
    return MeshTri(p, t)


def boundary_nodes(mesh: MeshTri) -> np.ndarray:
    """Sorted indices of the vertices on ∂Ω (the constrained unknowns)."""
    return np.sort(mesh.boundary_nodes())


def fk_boundary_nodes(N: int) -> np.ndarray:
    """``boundary_nodes(friedrichs_keller(N, ...))`` from the vertex numbering alone: vertex (i, j)
    (index i (N + 1) + j) lies on ∂Ω iff i or j is 0 or N.  scikit-fem finds them through the
    mesh's facets, which at N = 1001 costs seconds and the memory of 3 N² edges.  The index type
    is scikit-fem's (``int32``, that of ``MeshTri.t``)."""
    i, j = np.divmod(np.arange((N + 1) ** 2, dtype=np.int32), np.int32(N + 1))
    return np.flatnonzero((i == 0) | (i == N) | (j == 0) | (j == N)).astype(np.int32)
