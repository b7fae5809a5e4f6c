"""P1 assembly with scikit-fem: ``A = K + c M`` and ``b_i = ∫ f φ_i``.

The load vector uses the 16-point degree-8 triangle rule (``intorder=8``), the
quadrature convention of the whole package.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementTriP1, LinearForm, MeshTri
from skfem.helpers import dot, grad
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

from signorini.problem import Problem

INTORDER = 8  # scikit-fem's 16-point degree-8 Dunavant rule


@BilinearForm
def _reaction_diffusion(u, v, w):
    """∫ ∇u·∇v + c u v"""
    return dot(grad(u), grad(v)) + w.c * u * v


def p1_basis(mesh: MeshTri, intorder: int = INTORDER) -> Basis:
    """The P1 basis on ``mesh`` with the package's quadrature order."""
    return Basis(mesh, ElementTriP1(), intorder=intorder)


def system_matrix(basis: Basis, c: float) -> sp.csr_matrix:
    """A = K + c M, i.e. the form ∫ ∇u·∇v + c u v, in one assembly pass."""
    if basis.quadrature[1].size > 3:  # P1 products are quadratic: a degree-2 rule is exact
        basis = Basis(basis.mesh, basis.elem, intorder=2)
    A = _reaction_diffusion.assemble(basis, c=float(c)).tocsr()
    A.sum_duplicates()
    A.sort_indices()
    return A


CHUNK_ELEMENTS = 1 << 17  # triangles per assembly chunk: bounds the quadrature data to ~0.5 GiB


def load_vector(target: Basis | MeshTri, problem: Problem, chunk: int = CHUNK_ELEMENTS) -> np.ndarray:
    """b_i = ∫ f φ_i, assembled over chunks of triangles.

    ``target`` is a P1 basis (its quadrature rule is used) or a mesh (the package's
    degree-8 rule); chunking keeps the 16-point quadrature data of N = 2001 in memory.
    """

    @LinearForm
    def _load(v, w):
        return problem.f(w.x) * v

    if isinstance(target, Basis):
        mesh, quadrature = target.mesh, target.quadrature
    else:
        mesh, quadrature = target, get_quadrature(RefTri, INTORDER)
    n_el = mesh.t.shape[1]
    b = np.zeros(mesh.p.shape[1])
    for start in range(0, n_el, chunk):
        elements = np.arange(start, min(n_el, start + chunk))
        b += _load.assemble(Basis(mesh, ElementTriP1(), quadrature=quadrature, elements=elements))
    return b


def assemble(mesh: MeshTri, problem: Problem) -> tuple[sp.csr_matrix, np.ndarray]:
    """(A, b) for -Δu + c u = f on ``mesh``."""
    return system_matrix(p1_basis(mesh, intorder=2), problem.c), load_vector(mesh, problem)
