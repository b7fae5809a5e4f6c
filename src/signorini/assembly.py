"""P1 assembly with scikit-fem: ``A = K + c M`` and ``b_i = ∫ f φ_i``.

The load vector uses the 16-point degree-8 triangle rule (``intorder=8``), the
quadrature convention of the whole package.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementTriP1, LinearForm, MeshTri
from skfem.helpers import dot, grad

from signorini.problem import Problem

INTORDER = 8  # scikit-fem's 16-point degree-8 Dunavant rule


@BilinearForm
def _stiffness(u, v, w):
    """∫ ∇u·∇v"""
    return dot(grad(u), grad(v))


@BilinearForm
def _mass(u, v, w):
    """∫ u v"""
    return u * v


def p1_basis(mesh: MeshTri, intorder: int = INTORDER) -> Basis:
    """The P1 basis on ``mesh`` with the package's quadrature order."""
    return Basis(mesh, ElementTriP1(), intorder=intorder)


def system_matrix(basis: Basis, c: float) -> sp.csr_matrix:
    """A = K + c M, i.e. the form ∫ ∇u·∇v + c u v."""
    # the P1 bilinear forms are integrated exactly with a low-order rule
    low = Basis(basis.mesh, basis.elem, intorder=2)
    K = _stiffness.assemble(low)
    M = _mass.assemble(low)
    A = (K + c * M).tocsr()
    A.sum_duplicates()
    A.sort_indices()
    return A


def load_vector(basis: Basis, problem: Problem) -> np.ndarray:
    """b_i = ∫ f φ_i with the basis' quadrature rule."""

    @LinearForm
    def _load(v, w):
        return problem.f(w.x) * v

    return _load.assemble(basis)


def assemble(mesh: MeshTri, problem: Problem) -> tuple[sp.csr_matrix, np.ndarray]:
    """(A, b) for -Δu + c u = f on ``mesh``."""
    basis = p1_basis(mesh)
    return system_matrix(basis, problem.c), load_vector(basis, problem)
