"""Friedrichs–Keller meshes (``signorini.fem.mesh``): counts, vertex numbering, triangle shapes,
diagonals, boundary nodes and jitter."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import same_bits as _same_bits

from signorini.fem.mesh import (
    DIAGONALS,
    boundary_edges,
    boundary_nodes,
    fk_boundary_nodes,
    friedrichs_keller,
    mesh_width,
    triangles_meeting_disc,
)

SIZES = [1, 2, 3, 8]


def signed_areas(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def edges_of(t: np.ndarray) -> np.ndarray:
    """Unique undirected edges (2, n_edges) of a triangle array."""
    e = np.hstack([t[[0, 1]], t[[1, 2]], t[[2, 0]]])
    return np.unique(np.sort(e, axis=0), axis=1)


# ---------------------------------------------------------------------------------
# meshes
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", SIZES)
def test_mesh_counts_and_width(N, diagonal):
    mesh = friedrichs_keller(N, diagonal)
    assert mesh.p.shape == (2, (N + 1) ** 2)
    assert mesh.t.shape == (3, 2 * N * N)
    assert mesh_width(N) == 1.0 / N
    assert edges_of(mesh.t).shape[1] == 3 * N * N + 2 * N  # N(N+1) horizontal + vertical each, N² diagonals
    assert np.unique(mesh.p.round(12), axis=1).shape[1] == (N + 1) ** 2


@pytest.mark.parametrize("N", SIZES)
def test_vertex_numbering_convention(N):
    """Vertex (i, j) sits at (i/N, j/N) with index i (N + 1) + j (interpolate_fk relies on it)."""
    mesh = friedrichs_keller(N)
    i, j = np.divmod(np.arange((N + 1) ** 2), N + 1)
    np.testing.assert_allclose(mesh.p, np.vstack([i / N, j / N]), rtol=0, atol=1e-15)


@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", SIZES)
def test_triangles_are_right_isosceles_with_area_h2_over_2(N, diagonal):
    mesh = friedrichs_keller(N, diagonal)
    h = mesh_width(N)
    area = signed_areas(mesh.p, mesh.t)
    # scikit-fem's MeshTri sorts each triangle's vertex indices, so the stored orientation
    # is mixed; the areas (what assembly and the norms use) are all h²/2
    np.testing.assert_allclose(np.abs(area), h * h / 2, rtol=1e-12)
    assert np.abs(area).sum() == pytest.approx(1.0, rel=1e-12)
    # two legs of length h and a hypotenuse h√2 in every triangle
    lengths = np.sort(
        np.array([np.linalg.norm(mesh.p[:, mesh.t[k]] - mesh.p[:, mesh.t[(k + 1) % 3]], axis=0) for k in range(3)]),
        axis=0,
    )
    np.testing.assert_allclose(lengths[:2], h, rtol=1e-12)
    np.testing.assert_allclose(lengths[2], h * math.sqrt(2), rtol=1e-12)


@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", [2, 5])
def test_triangles_cover_the_square_without_overlap(N, diagonal, rng):
    """Every random point lies in exactly one triangle (barycentric test)."""
    mesh = friedrichs_keller(N, diagonal)
    x = rng.uniform(0, 1, size=(2, 400))
    a, b, c = (mesh.p[:, mesh.t[k]] for k in range(3))
    det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    l1 = ((x[0][:, None] - a[0]) * (c[1] - a[1]) - (x[1][:, None] - a[1]) * (c[0] - a[0])) / det
    l2 = ((b[0] - a[0]) * (x[1][:, None] - a[1]) - (b[1] - a[1]) * (x[0][:, None] - a[0])) / det
    inside = (l1 > -1e-12) & (l2 > -1e-12) & (l1 + l2 < 1 + 1e-12)
    assert np.all(inside.sum(axis=1) == 1)


@pytest.mark.parametrize("N", [1, 4, 7])
def test_diagonal_direction(N):
    h = mesh_width(N)
    for diagonal, sign in (("sw_ne", 1.0), ("nw_se", -1.0)):
        mesh = friedrichs_keller(N, diagonal)
        e = edges_of(mesh.t)
        d = mesh.p[:, e[1]] - mesh.p[:, e[0]]
        diag = np.abs(np.hypot(d[0], d[1]) - h * math.sqrt(2)) < 1e-12
        assert diag.sum() == N * N  # one diagonal per cell
        # "/" diagonals: Δx Δy > 0 ; "\\" diagonals: Δx Δy < 0
        assert np.all(np.sign(d[0, diag] * d[1, diag]) == sign)


@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", SIZES)
def test_boundary_nodes(N, diagonal):
    mesh = friedrichs_keller(N, diagonal)
    B = boundary_nodes(mesh)
    assert B.size == 4 * N
    assert np.all(np.diff(B) > 0), "sorted and unique"
    x, y = mesh.p
    on_boundary = np.isclose(x, 0) | np.isclose(x, 1) | np.isclose(y, 0) | np.isclose(y, 1)
    np.testing.assert_array_equal(B, np.flatnonzero(on_boundary))


def test_jitter_moves_only_interior_nodes_reproducibly():
    N, jitter = 8, 0.3
    plain = friedrichs_keller(N)
    a = friedrichs_keller(N, jitter=jitter, seed=3)
    b = friedrichs_keller(N, jitter=jitter, seed=3)
    c = friedrichs_keller(N, jitter=jitter, seed=4)
    np.testing.assert_array_equal(a.p, b.p)
    assert not np.array_equal(a.p, c.p)
    B = boundary_nodes(plain)
    np.testing.assert_array_equal(a.p[:, B], plain.p[:, B])
    interior = np.setdiff1d(np.arange(plain.p.shape[1]), B)
    shift = np.abs(a.p[:, interior] - plain.p[:, interior])
    assert shift.max() <= jitter / N + 1e-15 and shift.max() > 0
    # no triangle is inverted or degenerate: the orientation of each triangle is unchanged
    np.testing.assert_array_equal(a.t, plain.t)
    s0, s1 = signed_areas(plain.p, plain.t), signed_areas(a.p, a.t)
    assert np.all(np.sign(s0) == np.sign(s1)) and np.abs(s1).min() > 0.0
    assert np.abs(s1).sum() == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(N=0),
        dict(N=-3),
        dict(N=2.5),
        dict(N=True),
        dict(N="4"),
        dict(N=4, diagonal="x"),
        dict(N=4, jitter=0.5),
        dict(N=4, jitter=-0.1),
    ],
)
def test_invalid_mesh_arguments_raise(kwargs):
    with pytest.raises(ValueError):
        friedrichs_keller(**kwargs)


def test_numpy_integer_N_is_accepted():
    assert friedrichs_keller(np.int64(3)).t.shape == (3, 18)


@pytest.mark.parametrize("N", [1, 2, 7, 40])
def test_fk_boundary_nodes_are_the_mesh_boundary_nodes(N):
    for diagonal in DIAGONALS:
        assert _same_bits(fk_boundary_nodes(N), boundary_nodes(friedrichs_keller(N, diagonal)))


@pytest.mark.parametrize(
    "mesh",
    [
        *(friedrichs_keller(N, d) for N in (1, 2, 3, 8) for d in DIAGONALS),
        friedrichs_keller(9, "nw_se", jitter=0.3, seed=4),
        pytest.param("symmetric", id="union_jack"),
        pytest.param("sqsymmetric", id="criss_cross"),
    ],
)
def test_boundary_edges_are_scikit_fem_boundary_facets(mesh):
    """The edges on ∂Ω and their order are scikit-fem's, on meshes with and without diagonals
    that join two sides (the corner triangles of the union-jack mesh) and with interior edges
    whose vertices both lie on ∂Ω."""
    from skfem import MeshTri

    if isinstance(mesh, str):
        mesh = getattr(MeshTri, f"init_{mesh}")().refined(2)
    expected = mesh.facets[:, mesh.boundary_facets()]
    got = boundary_edges(mesh)
    assert got.dtype == expected.dtype and np.array_equal(got, expected)
    assert np.array_equal(boundary_nodes(mesh), np.sort(mesh.boundary_nodes()))


def test_boundary_edges_of_a_corner_cut_by_an_interior_edge():
    """Two triangles sharing the diagonal from (1, 0) to (0, 1): that edge has both vertices on ∂Ω
    but on two sides, and the corner square's hypotenuse inside a larger mesh is not on ∂Ω."""
    from skfem import MeshTri

    p = np.array([[0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]])
    mesh = MeshTri(p, np.array([[0, 1, 2], [1, 3, 2]]).T)
    assert {tuple(e) for e in boundary_edges(mesh).T} == {(0, 1), (0, 2), (1, 3), (2, 3)}


@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_a_triangle_not_meeting_the_disc_has_no_point_in_it(jitter, rng):
    """Every point of a triangle left out (random barycentric points, and its vertices) lies outside
    the open disc; the triangles kept are a strict subset."""
    mesh = friedrichs_keller(30, jitter=jitter)
    centre, radius = np.array([0.5, 0.0]), 0.27
    keep = triangles_meeting_disc(mesh.p, mesh.t, (centre, radius))
    lam = rng.dirichlet(np.ones(3), size=200).T  # (3, 200)
    lam = np.hstack([lam, np.eye(3)])
    x = np.einsum("dke,kq->deq", mesh.p[:, mesh.t], lam)
    inside = (np.hypot(x[0] - centre[0], x[1] - centre[1]) < radius).any(axis=1)
    assert np.all(keep[inside]) and 0 < keep.sum() < keep.size


@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_fk_triangles_are_the_arrays_of_the_mesh_without_scikit_fem(diagonal):
    """``fk_triangles`` gives the vertices and triangles of ``friedrichs_keller`` (what the norms read
    of a mesh), the same values and types, and refuses what it refuses."""
    from signorini.fem.mesh import fk_triangles

    mesh, arrays = friedrichs_keller(7, diagonal), fk_triangles(7, diagonal)
    for ours, theirs in ((arrays.p, mesh.p), (arrays.t, mesh.t)):
        assert ours.dtype == theirs.dtype and np.array_equal(ours, theirs)
    for bad in ((0, diagonal), (7, "diagonal")):
        with pytest.raises(ValueError):
            fk_triangles(*bad)
