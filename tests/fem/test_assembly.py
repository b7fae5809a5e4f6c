"""The P1 system matrix and load vector (``signorini.fem.assembly``): A = K + c M, the degree-8 load
vector, assembly over chunks of triangles, and the Friedrichs–Keller stencil equal to scikit-fem's
assembly bit for bit."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
import scipy.sparse as sp
from helpers import same_bits as _same_bits
from skfem import BilinearForm, LinearForm
from skfem.helpers import dot, grad

from signorini.fem.assembly import (
    CHUNK_ELEMENTS,
    INTORDER,
    assemble,
    assemble_bilinear_form,
    assemble_linear_form,
    chunk_bases,
    fk_stencil_matrix,
    load_vector,
    p1_basis,
    system_matrix,
)
from signorini.fem.mesh import DIAGONALS, boundary_nodes, friedrichs_keller, mesh_width
from signorini.fem.problem import Problem, ProblemBase

# ---------------------------------------------------------------------------------
# assembly: A = K + c M
# ---------------------------------------------------------------------------------


def lumped_mass(mesh) -> np.ndarray:
    """∫ φ_i = (number of triangles at vertex i) · |T| / 3 on a uniform FK mesh."""
    h = 1.0 / (round(math.sqrt(mesh.p.shape[1])) - 1)
    counts = np.bincount(mesh.t.ravel(), minlength=mesh.p.shape[1])
    return counts * (h * h / 2) / 3


@pytest.mark.parametrize("c", [0.0, 1.0, 3.5])
@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_system_matrix_identities(c, diagonal):
    N = 6
    mesh = friedrichs_keller(N, diagonal)
    A = system_matrix(p1_basis(mesh), c)
    assert sp.issparse(A) and A.shape == (mesh.p.shape[1],) * 2
    assert abs(A - A.T).max() < 1e-14
    one = np.ones(A.shape[0])
    # K·1 = 0, so A·1 = c·M·1 = c·∫φ_i, and 1ᵀA1 = c |Ω| = c
    np.testing.assert_allclose(A @ one, c * lumped_mass(mesh), rtol=0, atol=1e-14)
    assert one @ A @ one == pytest.approx(c, abs=1e-13)
    # v = x₁ + 2 x₂ is P1: vᵀAv = ∫|∇v|² + c ∫v² = 5 + c · 8/3 exactly
    v = mesh.p[0] + 2 * mesh.p[1]
    assert v @ A @ v == pytest.approx(5.0 + c * 8.0 / 3.0, rel=1e-13)
    # discrete harmonicity of linear functions: (K v)_i = 0 at interior vertices
    K = system_matrix(p1_basis(mesh), 0.0)
    interior = np.setdiff1d(np.arange(v.size), boundary_nodes(mesh))
    np.testing.assert_allclose((K @ v)[interior], 0.0, atol=1e-13)


@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_stiffness_is_the_five_point_stencil_and_mass_has_the_p1_entries(diagonal):
    N = 5
    h = mesh_width(N)
    mesh = friedrichs_keller(N, diagonal)
    K = system_matrix(p1_basis(mesh), 0.0).toarray()
    M = system_matrix(p1_basis(mesh), 1.0).toarray() - K
    idx = lambda i, j: i * (N + 1) + j  # noqa: E731
    for i, j in [(1, 1), (2, 3), (4, 4)]:
        k = idx(i, j)
        assert K[k, k] == pytest.approx(4.0)
        for di, dj in [(1, 0), (-1, 0), (0, 1), (0, -1)]:
            assert K[k, idx(i + di, j + dj)] == pytest.approx(-1.0)
        assert np.count_nonzero(np.abs(K[k]) > 1e-12) == 5  # diagonal neighbours carry 0
        assert M[k, k] == pytest.approx(h * h / 2)  # 6 triangles × |T|/6
        assert np.count_nonzero(np.abs(M[k]) > 1e-15) == 7
        assert np.sort(M[k][np.abs(M[k]) > 1e-15])[:6] == pytest.approx([h * h / 12] * 6)


def test_system_matrix_is_positive_definite_for_c_positive():
    A = system_matrix(p1_basis(friedrichs_keller(5)), 1.0).toarray()
    assert np.linalg.eigvalsh(A).min() > 0.0


# ---------------------------------------------------------------------------------
# assembly: the load vector b_i = ∫ f φ_i
# ---------------------------------------------------------------------------------

# f = Σ coefficient · x₁^a x₂^b, total degree ≤ 7 so that f φ_i (degree ≤ 8) is integrated exactly
MONOMIALS = [(1.0, 0, 0), (2.0, 5, 0), (-1.0, 0, 7), (1.5, 3, 4), (-0.7, 2, 2), (0.4, 1, 6)]


class PolynomialSource(ProblemBase):
    """A problem with only ``f`` (and the defaults of ``ProblemBase``: all that ``load_vector`` uses)."""

    c = 0.0

    def f(self, x):
        return sum(k * x[0] ** a * x[1] ** b for k, a, b in MONOMIALS)


def exact_moment(da: int, db: int) -> float:
    """∫_Ω f x₁^da x₂^db over the unit square."""
    return sum(k / ((a + da + 1) * (b + db + 1)) for k, a, b in MONOMIALS)


def test_p1_basis_uses_the_16_point_degree_8_rule():
    basis = p1_basis(friedrichs_keller(2))
    assert INTORDER == 8
    assert basis.X.shape[1] == 16
    assert basis.W.sum() == pytest.approx(0.5)


@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", [3, 8])
def test_load_vector_is_exact_for_degree_7_sources(N, diagonal):
    mesh = friedrichs_keller(N, diagonal)
    b = load_vector(p1_basis(mesh), PolynomialSource())
    assert b.shape == (mesh.p.shape[1],)
    # Σ φ_i = 1, x₁ = Σ x₁(v_i) φ_i, x₂ likewise: three exact moments
    assert b.sum() == pytest.approx(exact_moment(0, 0), rel=1e-13)
    assert b @ mesh.p[0] == pytest.approx(exact_moment(1, 0), rel=1e-13)
    assert b @ mesh.p[1] == pytest.approx(exact_moment(0, 1), rel=1e-13)
    # entry by entry: a much higher-order rule gives the same vector
    b_ref = load_vector(p1_basis(mesh, intorder=16), PolynomialSource())
    np.testing.assert_allclose(b, b_ref, rtol=0, atol=1e-14 * np.abs(b_ref).max())


def test_load_vector_is_not_exact_beyond_degree_8():
    """Sanity check of the previous test: the rule really is of degree 8, not more."""

    class Degree9(ProblemBase):
        def f(self, x):
            return x[0] ** 9  # f φ has degree 10

    mesh = friedrichs_keller(2)
    b = load_vector(p1_basis(mesh), Degree9())
    b_ref = load_vector(p1_basis(mesh, intorder=16), Degree9())
    assert np.abs(b - b_ref).max() > 1e-9


def test_assemble_combines_matrix_and_load():
    problem = Problem(c=2.0)
    mesh = friedrichs_keller(10, "nw_se")
    A, b = assemble(mesh, problem)
    basis = p1_basis(mesh)
    assert abs(A - system_matrix(basis, 2.0)).max() == 0.0
    np.testing.assert_array_equal(b, load_vector(basis, problem))


def test_load_vector_of_the_manufactured_problem_converges_with_quadrature_order():
    """b for the real f: the degree-8 rule agrees with a degree-16 rule to high relative accuracy."""
    mesh = friedrichs_keller(20)
    problem = Problem()
    b8 = load_vector(p1_basis(mesh), problem)
    b16 = load_vector(p1_basis(mesh, intorder=16), problem)
    assert np.abs(b8 - b16).max() < 1e-4 * np.abs(b16).max()


# ---------------------------------------------------------------------------------
# assembly over chunks of triangles
# ---------------------------------------------------------------------------------

CHUNKS = [1, 7, 50, 10**6]  # one triangle per chunk, several uneven chunks, one chunk


@LinearForm
def _mixed_linear(v, w):
    """∫ (x₁² x₂ + w.k) v + sin(x₁) ∂₁v: values, gradients, coordinates and a parameter."""
    return (w.x[0] ** 2 * w.x[1] + w.k) * v + np.sin(w.x[0]) * v.grad[0]


@pytest.mark.parametrize("chunk", [2, 13, 18])
def test_chunk_bases_cover_every_triangle_once(chunk):
    mesh = friedrichs_keller(3)  # 18 triangles
    bases = list(chunk_bases(mesh, chunk))
    assert len(bases) == math.ceil(18 / chunk)
    np.testing.assert_array_equal(np.concatenate([b.tind for b in bases]), np.arange(18))
    for b in bases:
        assert b.X.shape[1] == 16 and b.N == mesh.p.shape[1]
        assert b.basis[0][0].shape == (b.tind.size, 16)  # quadrature data of the chunk only


@pytest.mark.parametrize("chunk", [0, -3, True])
def test_chunk_size_must_be_positive(chunk):
    with pytest.raises(ValueError, match="chunk"):
        list(chunk_bases(friedrichs_keller(2), chunk))


@pytest.mark.parametrize("chunk", CHUNKS)
@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_assemble_linear_form_equals_whole_mesh_assembly(chunk, diagonal):
    mesh = friedrichs_keller(7, diagonal, jitter=0.3)
    whole = _mixed_linear.assemble(p1_basis(mesh), k=0.25)
    b = assemble_linear_form(mesh, _mixed_linear, chunk, k=0.25)
    np.testing.assert_allclose(b, whole, rtol=0, atol=1e-15 * np.abs(whole).max())
    # a basis as target: its quadrature rule
    b2 = assemble_linear_form(p1_basis(mesh, intorder=3), _mixed_linear, chunk, k=0.25)
    whole2 = _mixed_linear.assemble(p1_basis(mesh, intorder=3), k=0.25)
    np.testing.assert_allclose(b2, whole2, rtol=0, atol=1e-15 * np.abs(whole2).max())


@pytest.mark.parametrize("chunk", CHUNKS)
def test_load_vector_does_not_depend_on_the_chunk_size(chunk):
    mesh = friedrichs_keller(9, "nw_se")
    problem = Problem(x0=0.47, c=2.0)
    whole = LinearForm(lambda v, w: problem.f(w.x) * v).assemble(p1_basis(mesh))
    b = load_vector(mesh, problem, chunk)
    np.testing.assert_allclose(b, whole, rtol=0, atol=1e-14 * np.abs(whole).max())


@BilinearForm
def _weighted_laplace(u, v, w):
    return (1.0 + w.x[0]) * dot(grad(u), grad(v)) + w.x[1] * u * v


@pytest.mark.parametrize("chunk", CHUNKS)
@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_chunked_bilinear_forms_equal_whole_mesh_assembly(chunk, diagonal):
    mesh = friedrichs_keller(6, diagonal, jitter=0.2)
    whole = _weighted_laplace.assemble(p1_basis(mesh, intorder=4)).tocsr()
    A = assemble_bilinear_form(mesh, _weighted_laplace, chunk, intorder=4)
    assert A.format == "csr" and A.has_sorted_indices
    assert abs(A - whole).max() <= 1e-15 * abs(whole).max()
    A_sys = system_matrix(mesh, 1.5, chunk=chunk)
    A_ref = system_matrix(p1_basis(mesh), 1.5)
    assert abs(A_sys - A_ref).max() <= 1e-15 * abs(A_ref).max()
    assert A_sys.nnz == A_ref.nnz  # same sparsity pattern


@pytest.mark.parametrize("c", [0.0, 1.0, 2.5, 1e-3, 1e6])
@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", [1, 2, 3, 5, 17, 60])
def test_fk_stencil_matrix_is_scikit_fems_matrix_without_the_coordinates_round_off(N, diagonal, c):
    """Sparsity and index types are scikit-fem's (c = 0 drops the exact zeros of K between the
    acute vertices as scipy's ``eliminate_zeros`` does); the values differ by the round-off of the
    linspace coordinates in scikit-fem's, which grows like N units in the last place; bands of 1
    and 3 grid lines cut the mesh into pieces of every vertex class."""
    mesh = friedrichs_keller(N, diagonal)
    ref = system_matrix(p1_basis(mesh, intorder=2), c)
    for band in (1, 3, 64):
        A = fk_stencil_matrix(mesh, N, c, band)
        assert A.shape == ref.shape and A.has_canonical_format
        for part in ("indptr", "indices"):
            assert _same_bits(getattr(A, part), getattr(ref, part)), (part, band)
        assert np.all(np.abs(A.data - ref.data) <= 4 * N * np.spacing(np.abs(ref.data))), band


def _exact_system(N: int, diagonal: str, c: Fraction) -> dict[tuple[int, int], Fraction]:
    """``K + c M`` in rational arithmetic on the grid ``i/N``: the P1 element matrices of right
    triangles of legs ``h`` (stiffness from the edge vectors, mass ``|T| (1 + δ_ij) / 12``)."""
    mesh = friedrichs_keller(N, diagonal)
    area = Fraction(1, 2 * N * N)
    entries: dict[tuple[int, int], Fraction] = {}
    for tri in mesh.t.T:
        P = [np.divmod(int(v), N + 1) for v in tri]
        edges = [(P[(k + 2) % 3][0] - P[(k + 1) % 3][0], P[(k + 2) % 3][1] - P[(k + 1) % 3][1]) for k in range(3)]
        for i in range(3):
            for j in range(3):
                dot = Fraction(edges[i][0] * edges[j][0] + edges[i][1] * edges[j][1], N * N)
                value = dot / (4 * area) + c * area * (1 + (i == j)) / 12
                key = (int(tri[i]), int(tri[j]))
                entries[key] = entries.get(key, Fraction(0)) + value
    return entries


def test_fk_stencil_matrix_is_exact_to_a_few_units_in_the_last_place_where_scikit_fems_is_not():
    """Against the system in rational arithmetic (N = 60, c = 1.5): the stencil's entries within 2
    units in the last place; scikit-fem's, from the rounded coordinates, off by far more."""
    N, c = 60, 1.5
    mesh = friedrichs_keller(N)
    exact = _exact_system(N, "sw_ne", Fraction(c))
    A, ref = fk_stencil_matrix(mesh, N, c).tocoo(), system_matrix(p1_basis(mesh, intorder=2), c).tocoo()
    for M, bound in ((A, 2), (ref, None)):
        values = np.array([float(exact[int(i), int(j)]) for i, j in zip(M.row, M.col, strict=True)])
        ulps = np.abs(M.data - values) / np.spacing(np.abs(values))
        if bound is not None:
            assert ulps.max() <= bound
        else:
            assert ulps.max() >= 10


def test_fk_stencil_matrix_rejects_a_mesh_of_another_size():
    with pytest.raises(ValueError, match="Friedrichs–Keller"):
        fk_stencil_matrix(friedrichs_keller(4), 5, 1.0)


@pytest.mark.parametrize("chunk", [7, 1000, CHUNK_ELEMENTS])
@pytest.mark.parametrize("jitter", [0.0, 0.3])
@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", [1, 4, 30])
def test_load_vector_is_the_scikit_fem_linear_form_bit_for_bit(N, diagonal, jitter, chunk):
    mesh = friedrichs_keller(N, diagonal, jitter=jitter)
    for problem in (Problem(), Problem(x0=0.47, c=2.0)):
        form = LinearForm(lambda v, w, problem=problem: problem.f(w.x) * v)
        assert _same_bits(load_vector(mesh, problem, chunk), assemble_linear_form(mesh, form, chunk))
        basis = p1_basis(mesh, intorder=16)  # a basis as target: its rule
        assert _same_bits(load_vector(basis, problem, chunk), assemble_linear_form(basis, form, chunk))


@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_the_triangles_left_out_of_the_load_vector_have_no_quadrature_point_in_the_support(jitter):
    from signorini.fem.assembly import quadrature_chunks
    from signorini.fem.mesh import triangles_meeting_disc

    mesh = friedrichs_keller(40, jitter=jitter)
    centre, radius = np.array([0.47, 0.0]), 0.3
    keep = triangles_meeting_disc(mesh.p, mesh.t, (centre, radius))
    (_, x, _, _), *_ = quadrature_chunks(mesh, chunk=mesh.t.shape[1])
    inside = (np.hypot(x[0] - centre[0], x[1] - centre[1]) < radius).any(axis=1)
    assert np.all(keep[inside]) and 0 < keep.sum() < keep.size


def test_accumulating_over_the_band_of_a_chunk_equals_the_full_sum_bit_for_bit():
    """``accumulate`` adds a chunk's weights over the vertices it touches only: the same bytes as
    adding the full-length ``bincount``, over several chunks (repeated indices, an empty chunk)."""
    from signorini.fem.assembly import accumulate

    rng = np.random.default_rng(5)
    full, banded = np.zeros(1000), np.zeros(1000)
    for lo, size in ((200, 300), (0, 50), (950, 120), (400, 0), (210, 500)):
        index = np.minimum(lo + rng.integers(0, 60, size=size), 999)
        weights = rng.standard_normal(size)
        full += np.bincount(index, weights, minlength=1000)
        accumulate(banded, index, weights)
    assert banded.tobytes() == full.tobytes()
