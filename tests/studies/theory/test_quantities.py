"""The theory scene's quantities (``signorini.studies.theory.quantities``): Ritz projection and
supercloseness, the discrete H^{1/2}(∂Ω) norm, the contact set."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import LinearForm

from signorini.fem.assembly import p1_basis, system_matrix
from signorini.fem.discrete import build
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.problem import Problem, ProblemBase
from signorini.fem.solve import solve_discrete
from signorini.solvers.linalg import factorize
from signorini.studies.theory.quantities import (
    boundary_h12_norm,
    contact_set,
    h1_norm_p1,
    ritz_projection,
    ritz_rhs,
    ritz_solve,
    supercloseness,
    theory_quantities,
)


class _Linear(ProblemBase):
    """u = 1 + 2 x₁ - x₂ with reaction c: its Ritz projection is its interpolant."""

    c = 1.5

    def u(self, x):
        return 1.0 + 2.0 * x[0] - x[1]

    def grad_u(self, x):
        return np.stack([2.0 * np.ones_like(x[0]), -np.ones_like(x[0])])


def test_ritz_projection_reproduces_p1_functions():
    mesh = friedrichs_keller(6)
    r = ritz_projection(_Linear(), mesh)
    np.testing.assert_allclose(r, _Linear().u(mesh.p), atol=1e-12)


def _ritz_rhs_whole_mesh(problem, mesh):
    """The unchunked reference: the Ritz right-hand side on one degree-8 basis over the whole mesh."""

    @LinearForm
    def rhs(v, w):
        gu = problem.grad_u(w.x)
        return gu[0] * v.grad[0] + gu[1] * v.grad[1] + problem.c * problem.u(w.x) * v

    return rhs.assemble(p1_basis(mesh))


@pytest.mark.parametrize("chunk", [1, 37, 100, 10**6])
@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_chunked_ritz_rhs_equals_the_whole_mesh_assembly(chunk, diagonal):
    problem = Problem(x0=0.47, c=2.5)
    mesh = friedrichs_keller(12, diagonal, jitter=0.2)  # 288 triangles: 288, 8, 3 or 1 chunk(s)
    whole = _ritz_rhs_whole_mesh(problem, mesh)
    np.testing.assert_allclose(ritz_rhs(problem, mesh, chunk), whole, rtol=0, atol=1e-14 * np.abs(whole).max())


@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_ritz_projection_is_unchanged_by_chunking(diagonal):
    """R_h u and ‖R_h u - u_h‖ agree with the whole-mesh assembly (several chunks) to round-off."""
    problem = Problem(x0=0.47, c=2.5)
    mesh = friedrichs_keller(16, diagonal)  # 512 triangles
    reference = factorize(system_matrix(p1_basis(mesh), problem.c))(_ritz_rhs_whole_mesh(problem, mesh))
    for chunk in (37, 10**6):
        r = ritz_projection(problem, mesh, chunk=chunk)
        np.testing.assert_allclose(r, reference, rtol=0, atol=1e-13 * np.abs(reference).max())
    u_h = problem.u(mesh.p)
    assert supercloseness(problem, mesh, u_h, chunk=37) == pytest.approx(supercloseness(problem, mesh, u_h), rel=1e-12)


def test_ritz_solve_agrees_with_the_direct_factorisation_and_says_how():
    """CG with the AMG V-cycle gives the factorisation's R_h u (several levels at N = 64) from any
    start; started from u_h it needs fewer iterations, and ``info`` records them."""
    problem = Problem(x0=0.47, c=2.5)
    disc = build(problem, 64)
    rhs = ritz_rhs(problem, disc.mesh)
    direct = factorize(disc.A)(rhs)
    cold, warm = {}, {}
    from_zero = ritz_solve(disc.A, rhs, info=cold)
    u_h = solve_discrete(disc).u
    from_u_h = ritz_solve(disc.A, rhs, start=u_h, info=warm)
    for r in (from_zero, from_u_h):
        np.testing.assert_allclose(r, direct, rtol=0, atol=1e-12 * np.abs(direct).max())
    assert cold["levels"] > 1 and cold["energy_residual"] <= cold["tol"]
    assert 0 < warm["iterations"] < cold["iterations"]
    assert set(cold) >= {"method", "iterations", "energy_residual", "setup_s", "cg_s", "operator_complexity"}


def test_theory_quantities_use_the_discrete_problems_matrix():
    """With the discretise archive's A (K + c M, here c = 2.5: the H¹ norm assembles K + M apart)
    the supercloseness is the one of the assembled matrix, and the solve is recorded."""
    problem = Problem(x0=0.47, c=2.5)
    disc = build(problem, 32)
    u_h = solve_discrete(disc).u
    given = theory_quantities(problem, disc.mesh, u_h, disc.A)
    assembled = theory_quantities(problem, disc.mesh, u_h)
    assert given["supercloseness_H1"] == pytest.approx(assembled["supercloseness_H1"], rel=1e-9)
    assert given["ritz"]["iterations"] > 0


def test_h1_norm_of_p1_function_is_exact():
    mesh = friedrichs_keller(5)
    v = 1.0 + 2.0 * mesh.p[0] - mesh.p[1]
    # ‖v‖² = ∫ v² + |∇v|² = ∫ (1 + 2x - y)² + 5 over the unit square
    exact = np.sqrt(1 + 4 / 3 + 1 / 3 + 2 * 1 * 2 * 0.5 - 2 * 0.5 - 2 * 2 * 0.25 + 5)
    assert h1_norm_p1(mesh, v) == pytest.approx(exact, rel=1e-12)


def test_supercloseness_vanishes_for_the_ritz_projection():
    problem = Problem()
    mesh = friedrichs_keller(12)
    assert supercloseness(problem, mesh, ritz_projection(problem, mesh)) < 1e-12


class _BoundaryMode(ProblemBase):
    """u = cos(ω s) with s the arc length along ∂Ω (counter-clockwise from (0, 0)), ω = 2πk/4."""

    def __init__(self, k: int):
        self.omega = 2 * np.pi * k / 4.0

    def u(self, x):
        x1, x2 = x[0], x[1]
        s = np.where(x2 <= 1e-12, x1, np.where(x1 >= 1 - 1e-12, 1 + x2, np.where(x2 >= 1 - 1e-12, 3 - x1, 4 - x2)))
        return np.cos(self.omega * s)


@pytest.mark.parametrize("k", [1, 3])
def test_discrete_h12_norm_of_a_fourier_mode(k):
    """‖cos(ωs)‖²_{H^{1/2}} = (1 + ω²)^{1/2} · L/2 on a closed curve of length L = 4."""
    mode = _BoundaryMode(k)
    mesh = friedrichs_keller(64)
    value = boundary_h12_norm(mode, mesh, np.zeros(mesh.p.shape[1]), refine=2)
    exact = np.sqrt(np.sqrt(1 + mode.omega**2) * 2.0)
    assert value == pytest.approx(exact, rel=2e-3)


def test_contact_set_of_the_default_problem():
    problem = Problem()
    disc = build(problem, 41)
    u_h = solve_discrete(disc).u
    c = contact_set(problem, disc.mesh, u_h)
    assert c["n_contact_nodes"] == np.count_nonzero(u_h[disc.boundary] == 0.0)
    assert 0.0 < c["free_point_offset"] <= 1.0 / 41  # first contact node right of x0
    assert c["hausdorff_discrete_to_exact"] < 1e-3  # discrete contact ⊂ exact contact set


def test_theory_quantities_take_the_compiled_points_from_the_threshold_with_the_same_values(monkeypatch):
    from signorini.fem import point_kernels
    from signorini.fem import problem as problems
    from signorini.studies.theory import quantities

    problem = Problem()
    disc = build(problem, 40)
    u_h = solve_discrete(disc, "active_set").u
    numpy_values = quantities.theory_quantities(problem, disc.mesh, u_h, disc.A)
    calls = []
    real = point_kernels.manufactured_u_and_grad
    monkeypatch.setattr(point_kernels, "manufactured_u_and_grad", lambda *a: calls.append(1) or real(*a))
    monkeypatch.setattr(problems, "COMPILED_MIN_ELEMENTS", disc.mesh.t.shape[1])
    compiled_values = quantities.theory_quantities(problem, disc.mesh, u_h, disc.A)
    assert calls
    for values in (numpy_values, compiled_values):  # the Ritz solve's own timings apart
        values["ritz"] = {k: v for k, v in values["ritz"].items() if not k.endswith("_s")}
    assert repr(compiled_values) == repr(numpy_values)
