"""P1 assembly with scikit-fem: ``A = K + c M`` and ``b_i = ∫ f φ_i``.

The load vector uses the 16-point degree-8 triangle rule (``intorder=8``), the
quadrature convention of the whole package.  Linear (and, on request, bilinear)
forms are assembled over consecutive chunks of triangles, so that the quadrature
data of a mesh with millions of triangles never exists for the whole mesh at once.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementTriP1, LinearForm, MeshTri
from skfem.assembly import Dofs
from skfem.helpers import dot, grad
from skfem.mapping import MappingAffine
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

from signorini.fem.problem import Problem

INTORDER = 8  # scikit-fem's 16-point degree-8 Dunavant rule


@BilinearForm
def _reaction_diffusion(u, v, w):
    """∫ ∇u·∇v + c u v"""
    return dot(grad(u), grad(v)) + w.c * u * v


def p1_basis(mesh: MeshTri, intorder: int = INTORDER) -> Basis:
    """The P1 basis on ``mesh`` with the package's quadrature order."""
    return Basis(mesh, ElementTriP1(), intorder=intorder)


CHUNK_ELEMENTS = 1 << 17  # triangles per assembly chunk: bounds the quadrature data to ~0.5 GiB


def _mesh_and_quadrature(target: Basis | MeshTri, intorder: int) -> tuple[MeshTri, tuple[np.ndarray, np.ndarray]]:
    """The mesh of ``target`` and its quadrature rule (a basis's own, or the degree-``intorder`` rule)."""
    if isinstance(target, Basis):
        return target.mesh, target.quadrature
    return target, get_quadrature(RefTri, intorder)


def chunk_bases(target: Basis | MeshTri, chunk: int = CHUNK_ELEMENTS, intorder: int = INTORDER) -> Iterator[Basis]:
    """P1 bases on consecutive chunks ``T_k`` of at most ``chunk`` triangles, ``∪_k T_k = T_h``.

    ``target`` is a basis (its mesh and quadrature rule are used) or a mesh (the
    degree-``intorder`` rule).  Each basis carries the global P1 numbering, so a form
    assembled on it is the sum over ``T ∈ T_k`` of the element contributions, in
    global indices.  Only the chunk's affine maps and quadrature data are built
    (``MappingAffine(mesh, tind)``, no global DOF locations); the whole mesh only
    contributes its ``3 × #T`` element-to-DOF table, built once.
    """
    if isinstance(chunk, bool) or int(chunk) < 1:
        raise ValueError(f"chunk={chunk!r} must be a positive number of triangles")
    mesh, quadrature = _mesh_and_quadrature(target, intorder)
    elem = ElementTriP1()
    dofs = Dofs(mesh, elem)
    n_el = mesh.t.shape[1]
    for start in range(0, n_el, int(chunk)):
        elements = np.arange(start, min(n_el, start + int(chunk)))
        yield Basis(
            mesh,
            elem,
            mapping=MappingAffine(mesh, tind=elements),
            quadrature=quadrature,
            elements=elements,
            dofs=dofs,
            disable_doflocs=True,
        )


def assemble_linear_form(
    target: Basis | MeshTri, form: LinearForm, chunk: int = CHUNK_ELEMENTS, **params
) -> np.ndarray:
    """``b_i = ℓ(φ_i) = Σ_k Σ_{T ∈ T_k} ∫_T F(φ_i, w) dx`` for the P1 hat functions ``φ_i``.

    ``form`` is a scikit-fem ``LinearForm`` with integrand ``F(v, w)``; every triangle
    integral uses the quadrature rule of ``target`` (a basis), or the package's
    16-point degree-8 rule if ``target`` is a mesh.  The triangles are processed in
    chunks of at most ``chunk`` (``chunk_bases``), so the memory held at any time is
    that of one chunk's quadrature data plus the result; ``params`` are passed to
    ``form.assemble`` (e.g. coefficients ``w.c``).
    """
    mesh, _ = _mesh_and_quadrature(target, INTORDER)
    b = np.zeros(mesh.p.shape[1])
    for basis in chunk_bases(target, chunk):
        b += form.assemble(basis, **params)
        del basis  # free this chunk's quadrature data before the next chunk is built
    return b


def assemble_bilinear_form(
    target: Basis | MeshTri, form: BilinearForm, chunk: int = CHUNK_ELEMENTS, intorder: int = 2, **params
) -> sp.csr_matrix:
    """``A_ij = a(φ_j, φ_i) = Σ_k Σ_{T ∈ T_k} ∫_T F(φ_j, φ_i, w) dx`` for the P1 hat functions.

    The bilinear counterpart of ``assemble_linear_form``: the rule of ``target`` (a
    basis) or the degree-``intorder`` rule (a mesh; the default 2 is exact for the
    products of P1 functions and their gradients), chunks of at most ``chunk``
    triangles, the chunk matrices summed in CSR form (sorted, no duplicates).
    """
    A = None
    for basis in chunk_bases(target, chunk, intorder):
        A_k = form.assemble(basis, **params).tocsr()
        del basis  # free this chunk's quadrature data before the next chunk is built
        A = A_k if A is None else A + A_k
        del A_k
    A.sum_duplicates()
    A.sort_indices()
    return A


def system_matrix(target: Basis | MeshTri, c: float, chunk: int | None = None) -> sp.csr_matrix:
    """A = K + c M, i.e. the form ∫ ∇u·∇v + c u v, with a degree-2 rule (exact for P1).

    ``target`` is a P1 basis or a mesh.  ``chunk=None`` assembles in one pass over the
    whole mesh; an integer assembles over chunks of that many triangles
    (``assemble_bilinear_form``), the same matrix up to round-off in bounded memory.
    """
    if chunk is not None:
        mesh, quadrature = _mesh_and_quadrature(target, 2)
        target = mesh if quadrature[1].size > 3 else target
        return assemble_bilinear_form(target, _reaction_diffusion, chunk, intorder=2, c=float(c))
    basis = p1_basis(target, intorder=2) if isinstance(target, MeshTri) else target
    if basis.quadrature[1].size > 3:  # P1 products are quadratic: a degree-2 rule is exact
        basis = Basis(basis.mesh, basis.elem, intorder=2)
    A = _reaction_diffusion.assemble(basis, c=float(c)).tocsr()
    A.sum_duplicates()
    A.sort_indices()
    return A


def load_vector(target: Basis | MeshTri, problem: Problem, chunk: int = CHUNK_ELEMENTS) -> np.ndarray:
    """b_i = ∫ f φ_i, assembled over chunks of triangles (``assemble_linear_form``).

    ``target`` is a P1 basis (its quadrature rule is used) or a mesh (the package's
    degree-8 rule); chunking keeps the 16-point quadrature data of N = 2001 in memory.
    """

    @LinearForm
    def _load(v, w):
        return problem.f(w.x) * v

    return assemble_linear_form(target, _load, chunk)


def assemble(mesh: MeshTri, problem: Problem) -> tuple[sp.csr_matrix, np.ndarray]:
    """(A, b) for -Δu + c u = f on ``mesh``."""
    return system_matrix(p1_basis(mesh, intorder=2), problem.c), load_vector(mesh, problem)
