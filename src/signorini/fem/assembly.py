"""P1 assembly: ``A = K + c M`` and ``b_i = ∫ f φ_i``.

The load vector uses the 16-point degree-8 triangle rule (``intorder=8``), the
quadrature convention of the whole package.  Linear (and, on request, bilinear)
forms are assembled over consecutive chunks of triangles, so that the quadrature
data of a mesh with millions of triangles never exists for the whole mesh at once.

Two routes give the same arrays, bit for bit (tests/fem/test_assembly.py):

- scikit-fem's forms (``system_matrix``, ``assemble``) on any P1 mesh: per-element
  COO triplets, summed by scipy (``9 · #T`` triplets at once);
- on a Friedrichs–Keller mesh, ``fk_system_matrix`` writes the 7-point stencil of every
  vertex directly into CSR arrays, band by band of grid lines: the element matrices are
  computed with scikit-fem's floating-point operations (``_local_matrices``) and each
  entry is summed in the order scipy sums the triplets (``_row_templates``), so the
  memory is that of the result plus one band.  ``load_vector`` evaluates ``f`` once per
  quadrature point of a chunk (scikit-fem's ``LinearForm`` evaluates it once per basis
  function) with the same operations and the same order of summation.
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


def _local_matrices(p: np.ndarray, t: np.ndarray, c: float, intorder: int = 2) -> np.ndarray:
    """``data[j, i, e] = ∫_{T_e} ∇φ_j·∇φ_i + c φ_j φ_i`` (3, 3, E), computed with the operations of
    scikit-fem's ``_reaction_diffusion`` kernel on a degree-``intorder`` basis (bit-identical)."""
    X, W = get_quadrature(RefTri, intorder)
    q, nt = X.shape[1], t.shape[1]
    _, _, det, inv = _affine_maps(p, t)
    invDF = np.einsum("ijk,l->ijkl", inv, np.ones(q))
    zero = 0.0 * X[0]
    dphi = (np.array([-1.0 + zero, -1.0 + zero]), np.array([1.0 + zero, zero]), np.array([zero, 1.0 + zero]))
    grads = [np.einsum("ijkl,il->jkl", invDF, d) for d in dphi]
    values = [np.broadcast_to(v, (nt, q)) for v in p1_values(X)]
    dx = _quadrature_measure(det, W)
    data = np.empty((3, 3, nt))
    for j in range(3):
        for i in range(3):
            form = np.einsum("i...,i...", grads[j], grads[i]) + c * values[j] * values[i]
            data[j, i] = np.sum(form * dx, axis=1)
    return data


# --- the Friedrichs–Keller stencil ------------------------------------------------------------
#
# Vertex (a, b) of a Friedrichs–Keller mesh (``fem.mesh``) has index a (N + 1) + b; its row of A
# has one entry per neighbour (a + da, b + db), |da|, |db| ≤ 1 (7 of the 9 for either diagonal).
# scipy sums the triplets of one row in the order of its row sort (``csr_sort_indices``, an
# unstable sort for rows of more than 16 triplets), and that order depends only on the sequence
# of column keys: one sequence per vertex class (corner, edge, interior), the same everywhere
# else by translation.  ``_row_templates`` finds each class's triplet sequence on the mesh, and
# ``_sort_order`` asks scipy itself for the order in which it sums a sequence of keys.

# grid lines of vertices per band: bounds the working memory (docs/evidence/design-measurements.md#chunk-sizes)
STENCIL_BAND = 64


def _sort_order(keys: tuple[int, ...]) -> np.ndarray:
    """The permutation scipy's CSR row sort applies to a row whose column keys are ``keys``."""
    k = np.asarray(keys, dtype=np.int32)
    probe = sp.csr_matrix((np.arange(k.size, dtype=float), k, np.array([0, k.size])), shape=(1, 9))
    probe.has_sorted_indices = False  # force the sort scipy's COO-to-CSR conversion performs
    probe.sort_indices()
    return probe.data.astype(np.intp)


def _vertex_class(k: np.ndarray, N: int) -> np.ndarray:
    """0 on the first grid line, 2 on the last, 1 in between."""
    return np.where(k == 0, 0, np.where(k == N, 2, 1))


def _row_templates(mesh: MeshTri, N: int) -> dict[tuple[int, int], list[tuple[int, ...]]]:
    """Per vertex class (class of a, class of b): the triplets of a row of A in scipy's COO order
    (local column j, local row i, element), each as ``(j, i, type, di, dj, key)``: the element of
    type 0 (first N² triangles) or 1 on the cell (a + di, b + dj), the column key 3 (da + 1) + db + 1."""
    templates = {}
    for ca in sorted({int(c) for c in _vertex_class(np.arange(N + 1), N)}):
        for cb in sorted({int(c) for c in _vertex_class(np.arange(N + 1), N)}):
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
                            rows.append((j, int(i), e, kind, di, dj, 3 * (int(da) - a + 1) + int(db) - b + 1))
            rows.sort(key=lambda row: row[:3])
            templates[(ca, cb)] = [row[:2] + row[3:] for row in rows]
    return templates


def _band_rows(template, data, a, b, c0):
    """The triplet values (nodes, len(template)) of the rows of vertices (a, b) (element matrices
    ``data[kind]`` (3, 3, cells, N) of the cell rows from ``c0``)."""
    return np.stack([data[kind][j, i, a + di - c0, b + dj] for j, i, kind, di, dj, _ in template], axis=1)


def _stencil_sums(values: np.ndarray, keys: list[int], out: np.ndarray, present: np.ndarray, where) -> None:
    """Sum the triplets of rows with the key sequence ``keys`` as scipy does: zero triplets dropped
    (``eliminate_zeros``), the rest in scipy's row-sort order, each key's run summed left to right."""
    kept = values != 0.0
    codes = kept @ (1 << np.arange(len(keys), dtype=np.int64))
    for code in np.unique(codes):
        rows = np.flatnonzero(codes == code)
        live = [k for k in range(len(keys)) if (int(code) >> k) & 1]
        order = [live[k] for k in _sort_order(tuple(keys[k] for k in live))]
        for start in range(len(order)):
            key = keys[order[start]]
            if start and keys[order[start - 1]] == key:
                continue
            acc = values[rows, order[start]]
            for k in order[start + 1 :]:
                if keys[k] != key:
                    break
                acc = acc + values[rows, k]
            out[where[rows], key], present[where[rows], key] = acc, True


def fk_system_matrix(mesh: MeshTri, N: int, c: float, band: int = STENCIL_BAND) -> sp.csr_matrix:
    """``A = K + c M`` on the Friedrichs–Keller mesh ``mesh`` of ``N`` cells per side (either
    diagonal, jittered or not): the matrix of ``system_matrix(p1_basis(mesh, intorder=2), c)``,
    bit for bit (values, sparsity, index types), built from the 7-point stencil of each vertex
    in bands of ``band`` grid lines instead of from ``9 · #T`` triplets.  Memory: the CSR arrays
    (12 bytes per entry) plus one band's element matrices."""
    if mesh.p.shape[1] != (N + 1) ** 2 or mesh.t.shape[1] != 2 * N * N:
        raise ValueError(f"not a Friedrichs–Keller mesh with N={N} cells per side")
    templates, n = _row_templates(mesh, N), (N + 1) ** 2
    offsets = np.array([(da - 1) * (N + 1) + (db - 1) for da in range(3) for db in range(3)])
    cap = sum(len({row[-1] for row in tmpl}) for tmpl in templates.values()) * n  # ≥ nnz
    index = np.int32 if 7 * n < 2**31 else np.int64
    indptr, indices, data, nnz = np.zeros(n + 1, dtype=index), np.empty(min(cap, 7 * n), index), None, 0
    data = np.empty(indices.size)
    for a0 in range(0, N + 1, int(band)):
        a1 = min(N + 1, a0 + int(band))
        c0, c1 = max(a0 - 1, 0), min(a1, N)
        elements = [kind * N * N + np.arange(c0 * N, c1 * N) for kind in (0, 1)]
        local = [_local_matrices(mesh.p, mesh.t[:, e], float(c)).reshape(3, 3, c1 - c0, N) for e in elements]
        a, b = np.divmod(np.arange(a0 * (N + 1), a1 * (N + 1)), N + 1)
        out, present = np.zeros((a.size, 9)), np.zeros((a.size, 9), dtype=bool)
        cls = 3 * _vertex_class(a, N) + _vertex_class(b, N)
        for (ca, cb), tmpl in templates.items():
            where = np.flatnonzero(cls == 3 * ca + cb)
            if where.size:
                rows = _band_rows(tmpl, local, a[where], b[where], c0)
                _stencil_sums(rows, [row[-1] for row in tmpl], out, present, where)
        count = present.sum(axis=1)
        indptr[a0 * (N + 1) + 1 : a1 * (N + 1) + 1] = nnz + np.cumsum(count)
        m = int(count.sum())
        indices[nnz : nnz + m] = (np.arange(a0 * (N + 1), a1 * (N + 1))[:, None] + offsets)[present]
        data[nnz : nnz + m] = out[present]
        nnz += m
    if nnz < indices.size:  # zero entries were dropped (c = 0): the arrays at their exact size
        indices, data = indices[:nnz].copy(), data[:nnz].copy()
    A = sp.csr_matrix((data, indices, indptr), shape=(n, n))
    A.has_sorted_indices = True  # canonical by construction: sorted keys, one entry per key
    return A


def load_vector(target: Basis | MeshTri, problem: Problem, chunk: int = CHUNK_ELEMENTS) -> np.ndarray:
    """b_i = ∫ f φ_i, streamed over chunks of at most ``chunk`` triangles.

    ``target`` is a P1 basis (its quadrature rule is used) or a mesh (the package's
    degree-8 rule).  The value is that of ``assemble_linear_form`` with the form ``f v``,
    bit for bit: the same operations per triangle, the chunk's contributions added in
    scikit-fem's order (basis function, then triangle) and the chunks in order; but ``f``
    is evaluated once per quadrature point, and only the chunk's points exist at a time.
    """
    mesh, (X, _) = _mesh_and_quadrature(target, INTORDER)
    n = mesh.p.shape[1]
    b = np.zeros(n)
    for t, x, dx, _ in quadrature_chunks(target, chunk):
        fx = problem.f(x)
        values = [np.broadcast_to(v, dx.shape) for v in p1_values(X)]
        weights = np.concatenate([np.sum(fx * v * dx, axis=1) for v in values])
        b += np.bincount(t.ravel(), weights, minlength=n)  # sequential, as scipy's COO-to-dense sum
        del x, fx, dx, weights
    return b


def quadrature_chunks(
    target: Basis | MeshTri, chunk: int = CHUNK_ELEMENTS, intorder: int = INTORDER
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per chunk of at most ``chunk`` consecutive triangles ``t`` (3, E): the quadrature points
    ``x`` (2, E, q), the weights ``|det A| w_q`` (E, q) and the inverse maps ``A⁻¹`` (2, 2, E),
    with scikit-fem's operations (``MappingAffine``) and the rule of ``target`` (a basis's own, or
    the degree-``intorder`` rule of a mesh); only one chunk's arrays exist at a time."""
    if isinstance(chunk, bool) or int(chunk) < 1:
        raise ValueError(f"chunk={chunk!r} must be a positive number of triangles")
    mesh, (X, W) = _mesh_and_quadrature(target, intorder)
    n_el = mesh.t.shape[1]
    for start in range(0, n_el, int(chunk)):
        t = mesh.t[:, start : min(n_el, start + int(chunk))]
        A, shift, det, inv = _affine_maps(mesh.p, t)
        x = (np.einsum("ijk,jl", A, X).T + shift.T).T  # MappingAffine.F
        yield t, x, _quadrature_measure(det, W), inv


def assemble(mesh: MeshTri, problem: Problem) -> tuple[sp.csr_matrix, np.ndarray]:
    """(A, b) for -Δu + c u = f on ``mesh``."""
    return system_matrix(p1_basis(mesh, intorder=2), problem.c), load_vector(mesh, problem)
