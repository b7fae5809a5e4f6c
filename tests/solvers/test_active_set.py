"""The exact active-set solver, direct route (``signorini.solvers.active_set``): the KKT conditions
and the QP minimum, its named errors, vector warm starts, the factorisation backends, the bordered
solves, semicoercive and indefinite systems."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from helpers import check_kkt_independently, rel_max_diff

from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import BadInputError, KKTError, NotConvergedError
from signorini.solvers.active_set import active_set_solve
from signorini.solvers.linalg import factorize
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases

# ---------------------------------------------------------------------------------
# the exact solver
# ---------------------------------------------------------------------------------


def test_active_set_solution_satisfies_kkt(small_case):
    disc, res = small_case
    assert res.solver == "active_set" and res.certificate.ok
    assert res.certificate.worst <= 1e-10
    assert res.u.shape == disc.b.shape and res.lam.shape == disc.boundary.shape
    check_kkt_independently(disc.A, disc.b, disc.boundary, res.u, res.lam)
    # the contact set: boundary nodes, clamped to exactly zero
    assert np.all(np.isin(res.active, disc.boundary))
    assert np.all(res.u[res.active] == 0.0)
    assert res.iterations >= 1 and res.wall_time_s > 0.0
    json.dumps(res.summary())  # JSON-ready diagnostics


def test_active_set_solution_is_the_qp_minimiser(small_case):
    """No feasible perturbation lowers ½uᵀAu − bᵀu (first- and second-order check)."""
    disc, res = small_case
    A, b, B, u = disc.A, disc.b, disc.boundary, res.u
    J = lambda v: 0.5 * v @ (A @ v) - b @ v  # noqa: E731
    rng = np.random.default_rng(1)
    for _ in range(20):
        d = rng.normal(size=u.size)
        d[B] = np.abs(d[B])  # feasible directions at contact nodes point inwards
        for t in (1e-3, 1e-6):
            v = u + t * d * np.abs(u).max()
            assert J(v) >= J(u) - 1e-14 * abs(J(u))


def test_discrete_contact_set_resembles_the_continuous_one(cache):
    """On the bottom edge u_h > 0 well inside (x0 − R, x0) and u_h = 0 well inside (x0, x0 + R)."""
    disc, res = cache.discrete({}, 21), cache.solution({}, 21)
    x, y = disc.mesh.p
    bottom = disc.boundary[np.isclose(y[disc.boundary], 0.0)]
    lifted = bottom[(x[bottom] > 0.15) & (x[bottom] < 0.4)]
    contact = bottom[(x[bottom] > 0.6) & (x[bottom] < 0.9)]
    assert np.all(res.u[lifted] > 0.0)
    assert np.all(res.u[contact] == 0.0) and np.all(np.isin(contact, res.active))


# ---------------------------------------------------------------------------------
# truncated solves, bad input
# ---------------------------------------------------------------------------------


def test_truncated_active_set_solve_raises(cache):
    disc = cache.discrete({}, 11)
    cold = active_set_solve(disc.A, disc.b, disc.boundary)
    assert cold.iterations > 1, "precondition: the cold start needs more than one step"
    with pytest.raises(NotConvergedError):
        active_set_solve(disc.A, disc.b, disc.boundary, max_iter=1)
    with pytest.raises(NotConvergedError):
        solve_discrete(disc, warm_start=None, max_iter=1)


def test_active_set_missing_its_certificate_raises_kkt_error_with_residuals(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(KKTError) as info:
        active_set_solve(disc.A, disc.b, disc.boundary, kkt_tol=0.0)
    cert = info.value.certificate
    assert not cert.ok and cert.tol == 0.0 and cert.worst > 0.0
    assert "stationarity" in str(info.value)


def test_bad_warm_start_raises(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(ValueError):
        active_set_solve(disc.A, disc.b, disc.boundary, warm_start=np.zeros(disc.b.size - 1))
    with pytest.raises(ValueError):
        active_set_solve(disc.A, disc.b, disc.boundary, warm_start=np.full(disc.b.size, np.nan))
    with pytest.raises(ValueError, match="warm start"):
        solve_discrete(disc, warm_start="coarse")


@pytest.mark.parametrize("start", ["exact", "perturbed", "zero"])
def test_vector_warm_starts_converge_to_the_same_solution(cache, start):
    disc, exact = cache.discrete({}, 21), cache.solution({}, 21)
    w = {"exact": exact.u, "perturbed": exact.u + 1e-3 * np.sin(np.arange(exact.u.size)), "zero": 0 * exact.u}[start]
    res = active_set_solve(disc.A, disc.b, disc.boundary, warm_start=w)
    assert rel_max_diff(res.u, exact.u) <= 1e-12
    if start == "exact":
        assert res.iterations <= 2


@pytest.mark.parametrize("backend", ["pardiso", "cholmod", "superlu"])
def test_active_set_backends_agree(cache, backend):
    """Every installed factorisation backend gives the same certified solution."""
    from signorini.solvers.linalg import available_backends

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    disc, exact = cache.discrete({}, 21), cache.solution({}, 21)
    res = active_set_solve(disc.A, disc.b, disc.boundary, backend=backend)
    assert res.info["backend"] == backend
    assert rel_max_diff(res.u, exact.u) <= 1e-12


def test_bordered_solver_matches_a_direct_solve_of_the_clamped_system(cache):
    """``BorderedSolver`` (factor of Ã(W) plus one column per changed node) solves Ã(F) u = D r
    for free sets F that differ from W in both directions, exactly as a fresh factorisation."""
    from signorini.solvers.active_set import BorderedSolver, _clamped_values

    disc = cache.discrete({}, 21)
    A, B, n = disc.A.tocsr(), disc.boundary, disc.b.size
    rows = np.repeat(np.arange(n), np.diff(A.indptr))
    rng = np.random.default_rng(2)
    W = np.ones(n, dtype=bool)
    W[B[rng.random(B.size) < 0.5]] = False
    bordered = BorderedSolver(A, factorize(sp.csr_matrix((_clamped_values(A, rows, W), A.indices, A.indptr))), W)
    r = rng.normal(size=n)
    for changes in [0, 1, 3, 12]:
        F = W.copy()
        flip = rng.choice(B, size=changes, replace=False)
        F[flip] = ~F[flip]
        direct = spla.spsolve(sp.csc_matrix((_clamped_values(A, rows, F), A.indices, A.indptr)), np.where(F, r, 0.0))
        u = bordered(F, r)
        np.testing.assert_allclose(u, direct, rtol=0, atol=1e-12 * np.abs(direct).max())
        assert np.all(u[~F] == 0.0)
    # each changed node cost one column, cached across calls; b's solve is reused
    assert len(bordered.columns) <= 16
    solves = bordered.solves
    bordered(F, r)
    assert bordered.solves == solves


def test_zero_data_semicoercive_problem_gives_zero():
    """f ≡ 0, c = 0: A = K is singular and every u = t ≥ 0 solves the QP. The active-set
    method keeps the degenerate (u = λ = 0) boundary in contact and returns u = 0, certified."""
    from signorini.fem.assembly import p1_basis, system_matrix

    mesh = friedrichs_keller(12)
    K = system_matrix(p1_basis(mesh, intorder=2), 0.0)
    res = active_set_solve(K, np.zeros(K.shape[0]), boundary_nodes(mesh))
    assert res.certificate.ok and np.all(res.u == 0.0)


def test_unbounded_semicoercive_problem_raises_a_named_error():
    """c = 0 with a load pushing the whole boundary inwards (b > 0): u = t·1 drives the energy
    to −∞, no minimiser exists; a named error, never a raw LinAlgError or a "certified" u."""
    from signorini.fem.assembly import p1_basis, system_matrix

    mesh = friedrichs_keller(12)
    basis = p1_basis(mesh, intorder=2)
    K, M = system_matrix(basis, 0.0), system_matrix(basis, 1.0) - system_matrix(basis, 0.0)
    # CHOLMOD either stops at a zero pivot or returns u ~ 1e13 with an O(1) residual, which the
    # certificate must not pass off as a rounding floor
    with pytest.raises((NotConvergedError, KKTError)):
        active_set_solve(K, M @ np.ones(K.shape[0]), boundary_nodes(mesh))


def test_indefinite_matrix_that_the_active_set_would_accept_is_rejected():
    """A = K − M: every clamped block is definite, so before the PSD check the active-set method
    returned a "certified" KKT point of an unbounded QP (the constant direction lowers the energy)."""
    disc = stab_cases.build_case(stab_atlas.Case("bad", "bad_input", Problem().as_dict(), 21, corrupt="non_spd"))
    ones = np.ones(disc.b.size)
    assert ones @ (disc.A @ ones) < 0  # a feasible direction of negative curvature
    with pytest.raises(BadInputError):
        active_set_solve(disc.A, disc.b, disc.boundary)
