"""The discrete problem (``signorini.fem.discrete``): ``build`` and the P1 interpolation
``interpolate_fk`` on Friedrichs–Keller meshes."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import same_bits as _same_bits
from skfem import CellBasis, ElementTriP1

from signorini.fem.assembly import assemble
from signorini.fem.discrete import build, interpolate_fk
from signorini.fem.mesh import DIAGONALS, boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem

# ---------------------------------------------------------------------------------
# interpolate_fk
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("diagonal", DIAGONALS)
@pytest.mark.parametrize("N", [1, 3, 7])
def test_interpolate_fk_matches_scikit_fem_probes(N, diagonal, rng):
    mesh = friedrichs_keller(N, diagonal)
    values = rng.normal(size=mesh.p.shape[1])
    pts = np.hstack([rng.uniform(0, 1, size=(2, 300)), mesh.p, [[0, 1, 1, 0], [0, 0, 1, 1]]])
    probes = CellBasis(mesh, ElementTriP1()).probes(pts)
    np.testing.assert_allclose(interpolate_fk(N, diagonal, values, pts), probes @ values, rtol=0, atol=1e-13)
    np.testing.assert_allclose(interpolate_fk(N, diagonal, values, mesh.p), values, rtol=0, atol=1e-14)


@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_interpolate_fk_reproduces_linear_functions_across_meshes(diagonal, rng):
    """Prolongation from N = 5 to the vertices of N = 20 is exact for linear functions."""
    coarse, fine = friedrichs_keller(5, diagonal), friedrichs_keller(20, diagonal)
    lin = lambda x: 0.3 - 1.7 * x[0] + 2.2 * x[1]  # noqa: E731
    np.testing.assert_allclose(interpolate_fk(5, diagonal, lin(coarse.p), fine.p), lin(fine.p), atol=1e-14)


@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_interpolate_fk_by_blocks_gives_the_same_bits(diagonal, rng, monkeypatch):
    """Blocks of points (a few, and a last one cut short) give what one block gives, bit for bit."""
    import signorini.fem.discrete as discrete

    mesh = friedrichs_keller(11, diagonal)
    values, pts = rng.normal(size=mesh.p.shape[1]), np.hstack([rng.uniform(0, 1, size=(2, 250)), mesh.p])
    whole = interpolate_fk(11, diagonal, values, pts)
    monkeypatch.setattr(discrete, "INTERPOLATION_CHUNK", 64)
    assert _same_bits(interpolate_fk(11, diagonal, values, pts), whole)


@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_an_unbuilt_paper_mesh_has_the_vertices_of_the_built_one(diagonal):
    from dataclasses import replace

    disc = build(Problem(), 13, diagonal)
    assert _same_bits(replace(disc, mesh=None).vertices, disc.mesh.p) and disc.vertices is disc.mesh.p


def test_build_bundles_a_consistent_discrete_problem():
    problem = Problem(x0=0.47)
    disc = build(problem, 9, "nw_se")
    assert disc.N == 9 and disc.diagonal == "nw_se" and disc.problem is problem
    np.testing.assert_array_equal(disc.boundary, boundary_nodes(disc.mesh))
    A, b = assemble(friedrichs_keller(9, "nw_se"), problem)
    assert abs(disc.A - A).max() <= 1e-14 * abs(A).max()  # the exact stencil (tests/fem/test_assembly.py)
    np.testing.assert_array_equal(disc.b, b)


@pytest.mark.parametrize("diagonal", DIAGONALS)
def test_build_is_the_scikit_fem_assembly_without_the_coordinates_round_off(diagonal):
    """The load vector and the sparsity bit for bit; the matrix's values within the round-off of
    the mesh's coordinates in scikit-fem's (a few units in the last place per cell per side)."""
    problem = Problem(x0=0.47, c=1.5)
    disc = build(problem, 23, diagonal)
    A, b = assemble(friedrichs_keller(23, diagonal), problem)
    for part in ("indptr", "indices"):
        assert _same_bits(getattr(disc.A, part), getattr(A, part))
    assert np.all(np.abs(disc.A.data - A.data) <= 4 * 23 * np.spacing(np.abs(A.data)))
    assert _same_bits(disc.b, b)
    assert _same_bits(disc.boundary, boundary_nodes(disc.mesh))
