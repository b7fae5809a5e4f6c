"""P1 assembly: ``A = K + c M`` and ``b_i = ∫ f φ_i``.

The load vector uses the 16-point degree-8 triangle rule (``intorder=8``), the
quadrature convention of the whole package.  Linear (and, on request, bilinear)
forms are assembled over consecutive chunks of triangles, so that the quadrature
data of a mesh with millions of triangles never exists for the whole mesh at once.

Two routes give the system:

- scikit-fem's forms (``system_matrix``, ``assemble``) on any P1 mesh: per-element
  COO triplets, summed by scipy (``9 · #T`` triplets at once);
- on an unjittered Friedrichs–Keller mesh, ``fk_stencil_matrix`` writes the 7-point stencil of
  every vertex directly into CSR arrays, band by band of grid lines: every triangle is a right
  triangle of legs ``h``, so each class of vertex (corner, edge, interior) has one stencil, exact
  up to one rounding of the mass term (scikit-fem's entries carry the round-off of the mesh's
  coordinates, up to about ``N`` units in the last place); the sparsity and index types are
  scikit-fem's.  ``load_vector`` evaluates ``f`` once per quadrature point of a chunk
  (scikit-fem's ``LinearForm`` evaluates it once per basis function) with the same operations and
  the same order of summation, bit for bit, and leaves out the triangles outside the support of ``f``.
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

from signorini.fem.mesh import triangles_meeting_disc
from signorini.fem.problem import Problem

INTORDER = 8  # scikit-fem's 16-point degree-8 Dunavant rule


@BilinearForm
def _reaction_diffusion(u, v, w):
    """∫ ∇u·∇v + c u v"""
    return dot(grad(u), grad(v)) + w.c * u * v


def p1_basis(mesh: MeshTri, intorder: int = INTORDER) -> Basis:
    """The P1 basis on ``mesh`` with the package's quadrature order."""
    return Basis(mesh, ElementTriP1(), intorder=intorder)


# triangles per assembly chunk: bounds the quadrature data (docs/evidence/design-measurements.md#chunk-sizes)
CHUNK_ELEMENTS = 1 << 17


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


def _affine_maps(p: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``A`` (2, 2, E), ``b`` (2, E), ``det A`` and ``A⁻¹`` of the affine maps of triangles ``t``:
    the operations of scikit-fem's ``MappingAffine`` (bit-identical values)."""
    nt = t.shape[1]
    A, b = np.empty((2, 2, nt)), np.empty((2, nt))
    for i in range(2):
        b[i] = p[i, t[0]]
        for j in range(2):
            A[i, j] = p[i, t[j + 1]] - p[i, t[0]]
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    inv = np.empty((2, 2, nt))
    inv[0, 0], inv[0, 1] = A[1, 1] / det, -A[0, 1] / det
    inv[1, 0], inv[1, 1] = -A[1, 0] / det, A[0, 0] / det
    return A, b, det, inv


def p1_values(X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The P1 shape functions at reference points ``X`` (``ElementTriP1.lbasis``)."""
    x, y = X
    return 1.0 - x - y, x, y


def _quadrature_measure(det: np.ndarray, W: np.ndarray) -> np.ndarray:
    """``|det A| w_q`` (E, q), laid out as scikit-fem's ``CellBasis.dx`` (the layout fixes the
    order in which ``np.sum`` adds the quadrature points)."""
    q = W.shape[-1]
    return np.abs(np.tile(det, (q, 1)).T) * np.broadcast_to(W, (det.shape[0], q))


# --- the Friedrichs–Keller stencil ------------------------------------------------------------
#
# Vertex (a, b) of a Friedrichs–Keller mesh (``fem.mesh``) has index a (N + 1) + b; its row of A
# has one entry per neighbour (a + da, b + db), |da|, |db| ≤ 1 (7 of the 9 for either diagonal),
# and the same entries as every vertex of its class (corner, edge, interior): ``_row_templates``
# finds each class's element contributions on the mesh.

# grid lines of vertices per band: bounds the working memory (docs/evidence/design-measurements.md#chunk-sizes)
STENCIL_BAND = 64


def _vertex_class(k: np.ndarray, N: int) -> np.ndarray:
    """0 on the first grid line, 2 on the last, 1 in between."""
    return np.where(k == 0, 0, np.where(k == N, 2, 1))


def _row_templates(mesh: MeshTri, N: int) -> dict[tuple[int, int], list[tuple[int, ...]]]:
    """Per vertex class (class of a, class of b): the element contributions to a row of A, each as
    ``(j, i, type, di, dj, key)``: entry (i, j) of the element matrix of the element of type 0
    (first N² triangles) or 1 on the cell (a + di, b + dj), whose local vertex i is the row's vertex
    and j its neighbour with the column key 3 (da + 1) + db + 1."""
    templates = {}
    classes = sorted({int(c) for c in _vertex_class(np.arange(N + 1), N)})
    for ca in classes:
        for cb in classes:
            a, b = (0, 1, N)[ca], (0, 1, N)[cb]
            r, rows = a * (N + 1) + b, []
            for di, dj in ((-1, -1), (-1, 0), (0, -1), (0, 0)):
                if not (0 <= a + di < N and 0 <= b + dj < N):
                    continue
                for kind in (0, 1):
                    e = kind * N * N + (a + di) * N + (b + dj)
                    for i in np.flatnonzero(mesh.t[:, e] == r):
                        for j in range(3):
                            da, db = np.divmod(int(mesh.t[j, e]), N + 1)
                            rows.append((j, int(i), kind, di, dj, 3 * (int(da) - a + 1) + int(db) - b + 1))
            templates[(ca, cb)] = rows
    return templates


def _class_stencils(mesh: MeshTri, N: int, c: float) -> tuple[np.ndarray, np.ndarray]:
    """Per vertex class ``3 ca + cb`` (``_vertex_class``): the 9 entries of its row of ``A`` on the
    unjittered mesh, in exact form, and which of them exist.  On the grid of spacing ``h`` every
    triangle is a right triangle of legs ``h``: its stiffness matrix is ``e_i·e_j / 2`` for the edges
    ``e_i`` opposite its vertices in grid units (integers), its mass matrix ``h² (1 + δ_ij) / 24``.
    A triplet that is zero is dropped, as scipy's ``eliminate_zeros`` drops it (``c = 0``: the
    stiffness between the acute vertices)."""
    templates, mass = _row_templates(mesh, N), float(c) / (24.0 * N * N)
    stiffness2 = []  # twice the element stiffness matrix, per kind of triangle (integers)
    for kind in (0, 1):
        P = np.stack(np.divmod(mesh.t[:, kind * N * N].astype(np.int64), N + 1), axis=1)
        edges = [P[(i + 2) % 3] - P[(i + 1) % 3] for i in range(3)]
        stiffness2.append([[int(edges[i] @ edges[j]) for i in range(3)] for j in range(3)])
    values, present = np.zeros((9, 9)), np.zeros((9, 9), dtype=bool)
    for (ca, cb), template in templates.items():
        halves, masses = np.zeros(9, dtype=np.int64), np.zeros(9, dtype=np.int64)
        for j, i, kind, _, _, key in template:
            k2, m = stiffness2[kind][j][i], 1 + (i == j)
            if k2 / 2.0 + mass * m != 0.0:
                halves[key], masses[key], present[3 * ca + cb, key] = halves[key] + k2, masses[key] + m, True
        values[3 * ca + cb] = halves / 2.0 + mass * masses
    return values, present


def fk_stencil_matrix(mesh: MeshTri, N: int, c: float, band: int = STENCIL_BAND) -> sp.csr_matrix:
    """``A = K + c M`` on the unjittered Friedrichs–Keller mesh ``mesh`` of ``N`` cells per side
    (either diagonal) from the exact stencil of each class of vertex (``_class_stencils``): the
    matrix of scikit-fem's ``system_matrix(p1_basis(mesh, intorder=2), c)`` with its sparsity and
    index types and each value exact up to one rounding of the mass term, where scikit-fem's carry
    the round-off of the mesh's coordinates (within a few units of the last place per cell per side).
    A grid line of vertices has one of three row sequences (the first line, an inner one, the
    last): each is made once and copied into the CSR arrays, ``band`` lines at a time, shifted by
    the line's first vertex.  Memory: the CSR arrays plus one band's copies."""
    if mesh.p.shape[1] != (N + 1) ** 2 or mesh.t.shape[1] != 2 * N * N:
        raise ValueError(f"not a Friedrichs–Keller mesh with N={N} cells per side")
    values, present = _class_stencils(mesh, N, c)
    n, width = (N + 1) ** 2, N + 1
    offsets = np.array([(da - 1) * width + (db - 1) for da in range(3) for db in range(3)])
    classes = _vertex_class(np.arange(width), N)  # of the grid lines, and of the rows along one
    index = np.int32 if 7 * n < 2**31 else np.int64
    indptr = np.zeros(n + 1, dtype=index)
    lines = {}  # line class -> (columns relative to the line's first vertex, values) of its rows
    for ca in sorted({int(k) for k in classes}):
        mask = present[3 * ca + classes]
        lines[ca] = ((np.arange(width)[:, None] + offsets)[mask].astype(index), values[3 * ca + classes][mask])
    per_row = present.sum(axis=1)[3 * classes[:, None] + classes[None, :]]  # (line, row of the line)
    np.cumsum(per_row.ravel(), out=indptr[1:])
    indices, data = np.empty(int(indptr[-1]), dtype=index), np.empty(int(indptr[-1]))
    for a0 in range(0, width, int(band)):
        band_cls = classes[a0 : a0 + int(band)]
        for ca in np.unique(band_cls):
            a = np.flatnonzero(band_cls == ca) + a0  # consecutive lines of one class
            cols, vals = lines[int(ca)]
            lo, hi = int(indptr[a[0] * width]), int(indptr[(a[-1] + 1) * width])
            indices[lo:hi] = (cols[None, :] + (a.astype(index) * index(width))[:, None]).ravel()
            data[lo:hi] = np.tile(vals, a.size)
    A = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    A.has_sorted_indices = True  # canonical by construction: sorted keys, one entry per key
    return A


def accumulate(b: np.ndarray, index: np.ndarray, weights: np.ndarray) -> None:
    """``b += np.bincount(index, weights, minlength=b.size)``, bit for bit, over the entries
    ``index`` spans only: a chunk of consecutive triangles touches a narrow band of the vertices,
    and the sum over all of ``b`` per chunk would cost more than the chunk's own work on a fine
    mesh.  Outside the band the full sum adds ``+0.0``, which changes nothing in a ``b`` that holds
    no ``-0.0`` (one that starts at ``+0.0`` and only ever adds)."""
    if index.size == 0:
        return
    lo, hi = int(index.min()), int(index.max())
    b[lo : hi + 1] += np.bincount(index - lo, weights, minlength=hi - lo + 1)


def load_vector(target: Basis | MeshTri, problem: Problem, chunk: int = CHUNK_ELEMENTS) -> np.ndarray:
    """b_i = ∫ f φ_i, streamed over chunks of at most ``chunk`` triangles.

    ``target`` is a P1 basis (its quadrature rule is used) or a mesh (the package's
    degree-8 rule).  The value is that of ``assemble_linear_form`` with the form ``f v``,
    bit for bit: the same operations per triangle, the chunk's contributions added in
    scikit-fem's order (basis function, then triangle) and the chunks in order; but ``f``
    is evaluated once per quadrature point, only the chunk's points exist at a time, and
    triangles that cannot meet the problem's ``support`` are left out (their contributions are
    ``+0.0``, and adding ``+0.0`` changes no sum: ``b`` never holds ``-0.0``).
    """
    mesh, (X, _) = _mesh_and_quadrature(target, INTORDER)
    n = mesh.p.shape[1]
    b = np.zeros(n)
    for t, x, dx, _ in quadrature_chunks(target, chunk, support=problem.support()):
        fx = problem.f(x)
        values = [np.broadcast_to(v, dx.shape) for v in p1_values(X)]
        weights = np.concatenate([np.sum(fx * v * dx, axis=1) for v in values])
        accumulate(b, t.ravel(), weights)  # sequential, as scipy's COO-to-dense sum
        del x, fx, dx, weights
    return b


def quadrature_chunks(
    target: Basis | MeshTri,
    chunk: int = CHUNK_ELEMENTS,
    intorder: int = INTORDER,
    support: tuple[np.ndarray, float] | None = None,
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per chunk of at most ``chunk`` consecutive triangles ``t`` (3, E): the quadrature points
    ``x`` (2, E, q), the weights ``|det A| w_q`` (E, q) and the inverse maps ``A⁻¹`` (2, 2, E),
    with scikit-fem's operations (``MappingAffine``) and the rule of ``target`` (a basis's own, or
    the degree-``intorder`` rule of a mesh); only one chunk's arrays exist at a time.  With a
    ``support`` (centre, radius), only the chunk's triangles that may meet that disc."""
    if isinstance(chunk, bool) or int(chunk) < 1:
        raise ValueError(f"chunk={chunk!r} must be a positive number of triangles")
    mesh, (X, W) = _mesh_and_quadrature(target, intorder)
    n_el = mesh.t.shape[1]
    for start in range(0, n_el, int(chunk)):
        t = mesh.t[:, start : min(n_el, start + int(chunk))]
        if support is not None:
            t = t[:, triangles_meeting_disc(mesh.p, t, support)]
            if not t.shape[1]:
                continue
        A, shift, det, inv = _affine_maps(mesh.p, t)
        x = (np.einsum("ijk,jl", A, X).T + shift.T).T  # MappingAffine.F
        yield t, x, _quadrature_measure(det, W), inv


def assemble(mesh: MeshTri, problem: Problem) -> tuple[sp.csr_matrix, np.ndarray]:
    """(A, b) for -Δu + c u = f on ``mesh``."""
    return system_matrix(p1_basis(mesh, intorder=2), problem.c), load_vector(mesh, problem)
