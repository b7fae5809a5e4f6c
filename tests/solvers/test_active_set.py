"""The solvers of the discrete Signorini QP: the exact active-set solver, every installed
cvxpy QP solver as an independent cross-check, the KKT certificate, the named errors,
warm starts and the dispatcher."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from signorini.fem.discrete import build
from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import (
    SOLVERS,
    BadInputError,
    KKTError,
    NotConvergedError,
    active_set_solve,
    cvxpy_solve,
    installed_qp_solvers,
    kkt_certificate,
    solve,
)
from signorini.solvers.linalg import backend_name, factorize


def _expected_qp_solvers() -> list[str]:
    """cvxpy's installed QP-capable solvers, computed independently of the package."""
    import cvxpy as cp
    from cvxpy.reductions.solvers.defines import QP_SOLVERS

    return sorted(s for s in cp.installed_solvers() if s in set(QP_SOLVERS) | {"CLARABEL", "SCS"})


QP_SOLVER_NAMES = _expected_qp_solvers()

# Tight settings per solver, found by experiment on the SMALL_CASES meshes, and the
# relative max-norm agreement with the exact active-set solution each must reach.
# OSQP polishes onto the exact active set; HiGHS' QP solver is an active-set method too
# once its default Hessian regularisation (1e-7) is switched off.  The interior-point
# CLARABEL resolves the degenerate boundary nodes (u = λ = 0) to ~tol^{1/2}: at tol =
# 1e-12 it misses 1e-6 on one case (2.6e-6), at 1e-13 the worst case is ~5e-7.
TIGHT = {
    "OSQP": (dict(tol=1e-12), 1e-8),  # the package turns polishing on by default
    "HIGHS": (
        dict(qp_regularization_value=0.0, dual_feasibility_tolerance=1e-10, primal_feasibility_tolerance=1e-10),
        1e-8,
    ),
    "CLARABEL": (dict(tol=1e-13), 1e-6),
    "SCS": (dict(tol=1e-12), 1e-6),
}
# each solver's iteration-limit option, for the truncated solves
ITERATION_LIMIT = {"OSQP": "max_iter", "CLARABEL": "max_iter", "SCS": "max_iters", "HIGHS": "qp_iteration_limit"}


def rel_max_diff(u: np.ndarray, v: np.ndarray) -> float:
    return float(np.abs(u - v).max() / np.abs(v).max())


def check_kkt_independently(A, b, B, u, lam, tol=1e-10):
    """The KKT conditions recomputed here, not through ``kkt_certificate``."""
    r = A @ u - b
    scale = max(np.abs(A @ u).max(), np.abs(b).max())
    free = np.setdiff1d(np.arange(b.size), B)
    assert np.abs(r[free]).max() <= tol * scale, "stationarity at free nodes"
    assert np.abs(r[B] - lam).max() <= tol * scale, "λ = (A u − b)_B"
    assert u[B].min() >= -tol * np.abs(u).max(), "u_B ≥ 0"
    assert lam.min() >= -tol * scale, "λ ≥ 0"
    assert np.abs(u[B] * lam).max() <= tol * np.abs(u).max() * scale, "complementarity"


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
# cvxpy cross-checks
# ---------------------------------------------------------------------------------


def test_installed_qp_solvers():
    assert installed_qp_solvers() == QP_SOLVER_NAMES
    assert "CLARABEL" in QP_SOLVER_NAMES and "OSQP" in QP_SOLVER_NAMES


@pytest.mark.parametrize("qp_solver", QP_SOLVER_NAMES)
def test_cvxpy_solvers_agree_with_active_set(small_case, qp_solver):
    if qp_solver not in TIGHT:
        pytest.skip(f"no tight settings known for {qp_solver}; add them to TIGHT")
    disc, exact = small_case
    options, bound = TIGHT[qp_solver]
    res = cvxpy_solve(disc.A, disc.b, disc.boundary, solver=qp_solver, kkt_tol=1e-8, **options)
    assert res.certificate.ok and res.certificate.worst <= 1e-8
    assert res.solver == f"cvxpy_{qp_solver.lower()}"
    if qp_solver == "OSQP":
        assert res.info["options"].get("polish", res.info["options"].get("polishing")) == "True"
    assert rel_max_diff(res.u, exact.u) <= bound
    check_kkt_independently(disc.A, disc.b, disc.boundary, res.u, res.lam, tol=1e-8)
    json.dumps(res.summary())


@pytest.mark.parametrize("qp_solver", QP_SOLVER_NAMES)
def test_truncated_cvxpy_solve_raises(cache, qp_solver):
    if qp_solver not in ITERATION_LIMIT:
        pytest.skip(f"iteration-limit option of {qp_solver} unknown")
    disc = cache.discrete({}, 11)
    with pytest.raises((NotConvergedError, KKTError)):
        cvxpy_solve(disc.A, disc.b, disc.boundary, solver=qp_solver, **{ITERATION_LIMIT[qp_solver]: 2})


def test_cvxpy_solution_missing_its_certificate_raises_kkt_error(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(KKTError) as info:
        cvxpy_solve(disc.A, disc.b, disc.boundary, solver="CLARABEL", kkt_tol=1e-30)
    assert info.value.certificate.worst > 1e-30
    # ... and with check=False the (good) solution comes back with its failed certificate
    res = cvxpy_solve(disc.A, disc.b, disc.boundary, solver="CLARABEL", kkt_tol=1e-30, check=False)
    assert not res.certificate.ok


def test_unknown_cvxpy_solver_name_raises_value_error(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(ValueError, match="NOSUCHSOLVER"):
        cvxpy_solve(disc.A, disc.b, disc.boundary, solver="nosuchsolver")
    with pytest.raises(ValueError, match="NOSUCHSOLVER"):
        solve("cvxpy_nosuchsolver", disc.A, disc.b, disc.boundary)


def test_dispatcher_routes(cache):
    disc, exact = cache.discrete({}, 11), cache.solution({}, 11)
    assert SOLVERS == ("active_set", "multigrid", "auto", "cvxpy")
    assert solve("multigrid", disc.A, disc.b, disc.boundary, max_coarse=20).solver == "multigrid"
    assert solve("auto", disc.A, disc.b, disc.boundary).solver == "active_set"  # 144 unknowns: direct
    r1 = solve("active_set", disc.A, disc.b, disc.boundary)
    r2 = solve("cvxpy", disc.A, disc.b, disc.boundary, qp_solver="OSQP", tol=1e-12, warm_start=exact.u)
    r3 = solve("cvxpy_osqp", disc.A, disc.b, disc.boundary, tol=1e-12, warm_start=exact.u)
    r4 = solve_discrete(disc, "cvxpy", qp_solver="OSQP", tol=1e-12)
    assert r1.solver == "active_set" and r2.solver == r3.solver == r4.solver == "cvxpy_osqp"
    for r in (r1, r2, r3, r4):
        assert rel_max_diff(r.u, exact.u) <= 1e-8


def test_auto_route_takes_multigrid_from_the_crossover_on(monkeypatch, caplog):
    """``auto`` resolves by each mesh's size: with the crossover between the cascade's coarse
    mesh (N = 25: 676 unknowns) and the fine one (N = 101: 10 201), the coarse level is solved
    by the direct route and the fine one by multigrid, to the direct route's solution."""
    import logging

    import signorini.solvers as solvers

    monkeypatch.setattr(solvers, "MULTIGRID_FROM_UNKNOWNS", 5000)
    assert solvers.exact_route("auto", 4999) == "active_set" and solvers.exact_route("auto", 5000) == "multigrid"
    assert solvers.exact_route("multigrid", 10) == "multigrid"
    disc = build(Problem(), 101)
    with caplog.at_level(logging.INFO, logger="signorini.solvers"):
        result = solve_discrete(disc, "auto")
    loggers = {record.name for record in caplog.records}
    assert {"signorini.solvers.active_set", "signorini.solvers.multigrid"} <= loggers
    direct = solve_discrete(disc, "active_set")
    assert result.solver == "multigrid" and rel_max_diff(result.u, direct.u) <= 1e-12
    np.testing.assert_array_equal(np.sort(result.active), np.sort(direct.active))


def test_unknown_solver_name_raises_value_error_naming_it(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(ValueError, match="quadprog"):
        solve("quadprog", disc.A, disc.b, disc.boundary)
    with pytest.raises(ValueError, match="quadprog"):
        solve_discrete(disc, "quadprog")


# ---------------------------------------------------------------------------------
# truncated solves, certificates, bad input
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


def test_certificate_detects_perturbed_solutions(small_case):
    disc, res = small_case
    A, b, B, u, lam = disc.A, disc.b, disc.boundary, res.u, res.lam
    assert kkt_certificate(A, b, B, u, lam, 1e-10).ok
    scale = np.abs(u).max()
    interior = np.setdiff1d(np.arange(u.size), B)

    v = u.copy()
    v[interior[interior.size // 2]] += 1e-6 * scale  # breaks stationarity
    cert = kkt_certificate(A, b, B, v, lam, 1e-10)
    assert not cert.ok and cert.stationarity > 1e-10

    v = u.copy()
    v[res.active[0]] = -1e-6 * scale  # infeasible
    assert kkt_certificate(A, b, B, v, lam, 1e-10).primal > 1e-10

    strong = np.argmax(lam)  # a node with a strictly positive multiplier
    assert lam[strong] > 0
    v = u.copy()
    v[B[strong]] += 1e-6 * scale  # lifts a contact node: stationarity and complementarity break
    cert = kkt_certificate(A, b, B, v, lam, 1e-10)
    assert not cert.ok and cert.complementarity > 1e-10

    cert = kkt_certificate(A, b, B, u, -lam, 1e-10)  # wrong sign of the multiplier
    assert not cert.ok and cert.dual > 1e-10

    assert not kkt_certificate(A, b, B, np.full_like(u, np.nan), lam, 1e-10).ok


def test_certificate_is_scale_invariant(small_case):
    disc, res = small_case
    c1 = kkt_certificate(disc.A, disc.b, disc.boundary, res.u, res.lam, 1e-10)
    c2 = kkt_certificate(disc.A, 1e5 * disc.b, disc.boundary, 1e5 * res.u, 1e5 * res.lam, 1e-10)
    for name in ("stationarity", "primal", "dual", "complementarity"):
        # residuals at round-off level differ by a few ulps after scaling
        assert getattr(c2, name) == pytest.approx(getattr(c1, name), rel=1e-6, abs=1e-14)


def _bad_inputs(disc):
    A, b, B = disc.A, disc.b, disc.boundary
    nan_b = b.copy()
    nan_b[3] = np.nan
    inf_A = A.copy().tolil()
    inf_A[2, 2] = np.inf
    neg = A.copy().tolil()
    neg[5, 5] = -neg[5, 5]
    zero = A.copy().tolil()
    zero[5, 5] = 0.0
    return {
        "nan in b": (A, nan_b, B),
        "inf in A": (inf_A.tocsr(), b, B),
        "short b": (A, b[:-1], B),
        "non-square A": (A[:, :-1], b, B),
        "negative diagonal": (neg.tocsr(), b, B),
        "zero diagonal": (zero.tocsr(), b, B),
        "index out of range": (A, b, np.append(B, b.size)),
        "negative index": (A, b, np.append(B, -1)),
    }


BAD_INPUT_NAMES = list(_bad_inputs(build(Problem(), 3)))


@pytest.mark.parametrize("which", BAD_INPUT_NAMES)
def test_active_set_rejects_bad_input(cache, which):
    A, b, B = _bad_inputs(cache.discrete({}, 11))[which]
    with pytest.raises(BadInputError):
        active_set_solve(A, b, B)


@pytest.mark.parametrize("which", BAD_INPUT_NAMES)
def test_cvxpy_rejects_bad_input(cache, which):
    A, b, B = _bad_inputs(cache.discrete({}, 11))[which]
    with pytest.raises(BadInputError):
        cvxpy_solve(A, b, B, solver="OSQP")


def test_bad_input_error_is_a_value_error():
    assert issubclass(BadInputError, ValueError)


def test_bad_warm_start_raises(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(ValueError):
        active_set_solve(disc.A, disc.b, disc.boundary, warm_start=np.zeros(disc.b.size - 1))
    with pytest.raises(ValueError):
        active_set_solve(disc.A, disc.b, disc.boundary, warm_start=np.full(disc.b.size, np.nan))
    with pytest.raises(ValueError, match="warm start"):
        solve_discrete(disc, warm_start="coarse")


# ---------------------------------------------------------------------------------
# warm starts
# ---------------------------------------------------------------------------------


@pytest.fixture(scope="module", params=["sw_ne", "nw_se"])
def cascade_pair(request):
    """N = 101: large enough that the cascade really warm-starts (from N = 25)."""
    disc = build(Problem(), 101, request.param)
    return disc, solve_discrete(disc, warm_start="cascade"), solve_discrete(disc, warm_start=None)


def test_cascade_warm_start_gives_the_cold_solution(cascade_pair):
    disc, warm, cold = cascade_pair
    assert rel_max_diff(warm.u, cold.u) <= 1e-12
    np.testing.assert_array_equal(np.sort(warm.active), np.sort(cold.active))
    assert warm.certificate.ok and cold.certificate.ok
    check_kkt_independently(disc.A, disc.b, disc.boundary, warm.u, warm.lam)


def test_cascade_warm_start_saves_factorisations(cascade_pair):
    _, warm, cold = cascade_pair
    assert warm.info["factorizations"] <= cold.info["factorizations"]
    assert warm.iterations <= cold.iterations
    assert warm.info["factorizations"] >= 1 and warm.info["triangular_solves"] >= warm.info["factorizations"]


@pytest.mark.parametrize("start", ["exact", "perturbed", "zero"])
def test_vector_warm_starts_converge_to_the_same_solution(cache, start):
    disc, exact = cache.discrete({}, 21), cache.solution({}, 21)
    w = {"exact": exact.u, "perturbed": exact.u + 1e-3 * np.sin(np.arange(exact.u.size)), "zero": 0 * exact.u}[start]
    res = active_set_solve(disc.A, disc.b, disc.boundary, warm_start=w)
    assert rel_max_diff(res.u, exact.u) <= 1e-12
    if start == "exact":
        assert res.iterations <= 2


# ---------------------------------------------------------------------------------
# sparse factorisation
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("backend", ["auto", "superlu"])
def test_factorize_solves_spd_systems(cache, backend):
    A = sp.csc_matrix(cache.discrete({}, 21).A)
    rng = np.random.default_rng(0)
    y = rng.normal(size=A.shape[0])
    solve_ = factorize(A, backend)
    x = solve_(y)
    np.testing.assert_allclose(x, spla.spsolve(A, y), rtol=0, atol=1e-12 * np.abs(x).max())
    Y = rng.normal(size=(A.shape[0], 3))
    X = np.column_stack([solve_(Y[:, k]) for k in range(3)])
    np.testing.assert_allclose(A @ X, Y, atol=1e-10)


def test_factorisation_backend_names():
    from signorini.solvers.linalg import available_backends

    assert backend_name("superlu") == "superlu"
    assert backend_name("auto") == available_backends()[0]
    with pytest.raises(ValueError):
        backend_name("mumps")


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


@pytest.mark.parametrize("backend", ["cholmod", "superlu"])
def test_factorize_solves_blocks_of_right_hand_sides(cache, backend):
    """(n, k) blocks are solved column by column in one call (the bordered columns rely on it)."""
    from signorini.solvers.linalg import available_backends

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    A = cache.discrete({}, 21).A
    Y = np.random.default_rng(1).normal(size=(A.shape[0], 4))
    X = factorize(A, backend)(Y)
    assert X.shape == Y.shape
    np.testing.assert_allclose(A @ X, Y, atol=1e-10)


@pytest.mark.parametrize("n", [50, 40_000])  # CHOLMOD: simplicial LDLᵀ, supernodal LLᵀ
@pytest.mark.parametrize("backend", ["cholmod", "superlu"])
def test_positive_definiteness_on_shifted_laplacians(n, backend):
    """The 1D Laplacian tridiag(-1, 2, -1) has eigenvalues in (0, 4): ``T + s I`` is positive
    definite for s > 0 and indefinite for -4 < s < 0, whatever factorisation CHOLMOD picks."""
    from signorini.solvers.linalg import available_backends, is_positive_definite

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n), format="csr")
    assert is_positive_definite(T + 0.5 * sp.identity(n), backend)
    assert not is_positive_definite(T - 0.5 * sp.identity(n), backend)
    assert not is_positive_definite(T - 3.0 * sp.identity(n), backend)


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


def test_fine_solve_costs_one_factorisation_and_few_solves():
    """The cascade's point at N = 101: one factorisation, and the changes of the active set
    after it cost a handful of triangular solves (not one Krylov solve per Newton step)."""
    disc = build(Problem(), 101)
    res = solve_discrete(disc)
    assert res.info["factorizations"] == 1
    assert res.info["triangular_solves"] <= 2 + res.info["correction_columns"] <= 12


def test_an_older_in_place_factor_refuses_to_solve(cache):
    """CHOLMOD refactorises in place (one symbolic analysis per pattern): after a second
    factorisation the first ``solve`` would silently use the new numbers, so it raises."""
    from signorini.solvers.linalg import Factorizer, available_backends

    if "cholmod" not in available_backends():
        pytest.skip("cholmod not installed")
    A = sp.csr_matrix(cache.discrete({}, 11).A)
    factorizer = Factorizer(A, "cholmod")
    first = factorizer(A.data)
    y = np.ones(A.shape[0])
    np.testing.assert_allclose(A @ first(y), y, atol=1e-12)
    second = factorizer(2.0 * A.data)
    np.testing.assert_allclose(2.0 * (A @ second(y)), y, atol=1e-12)
    with pytest.raises(RuntimeError, match="stale"):
        first(y)


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


def test_rounding_floor_is_capped():
    """The certificate's rounding floor ``16 ε ‖|A||u|‖∞/σ`` admits cancellation, not an
    exploded u: a residual of 0.5 is never certified, however large u is."""
    A = sp.csr_matrix(np.array([[1.0, -1.0], [-1.0, 1.0]]))  # K of one interval: A 1 = 0
    u = np.array([1e15, 1e15])  # A u cancels exactly; |A||u| = 2e15
    b = np.array([1.0, 1.0])  # relative stationarity ‖A u - b‖∞ / ‖b‖∞ = 1
    cert = kkt_certificate(A, b, np.array([0]), u, np.zeros(1), 1e-10)
    assert cert.floor > 1.0 and cert.stationarity == 1.0
    assert not cert.ok


def test_the_option_tables_match_the_installed_qp_solvers():
    """The config check knows OSQP's and SCS's settings without importing them: the tables must be
    what the installed packages accept (a new release with other settings fails here)."""
    import osqp.ext_builtin
    import scs

    from signorini.pipeline.solver_options import OSQP_SETTINGS, SCS_SETTINGS, route_options

    settings = osqp.ext_builtin.OSQPSettings()
    installed = {name for name in dir(settings) if not name.startswith("_")}
    assert set(OSQP_SETTINGS) == installed
    for name, kind in OSQP_SETTINGS.items():
        assert kind is object or isinstance(getattr(settings, name), kind), name
    data = {"P": sp.csc_matrix(np.eye(1)), "A": sp.csc_matrix(-np.eye(1)), "b": np.zeros(1), "c": np.ones(1)}
    values = {bool: False, int: 100, float: 1e-6, str: ""}
    scs.SCS(data, {"l": 1}, **{name: values[kind] for name, kind in SCS_SETTINGS.items() if kind is not str})
    scs.SCS(data, {"l": 1}, linear_solver="qdldl", write_data_filename=None, log_csv_filename=None)
    with pytest.raises(TypeError):
        scs.SCS(data, {"l": 1}, not_a_setting=1)
    assert "polishing" in route_options("cvxpy_osqp")[1] and "tol" in route_options("OSQP")[1]


def test_a_cascade_start_that_does_not_settle_falls_back_to_the_cold_start(caplog):
    """From the coarse interpolant of this problem the contact set grows by one node per Newton
    step and exceeds max_iter; the solve is repeated from the cold start, which settles."""
    import logging

    disc = build(Problem(x0=0.4142, R=0.3, A=10.0, c=1.0), 121, "sw_ne")
    with caplog.at_level(logging.WARNING, logger="signorini.fem.solve"):
        result = solve_discrete(disc)
    assert "cascade start did not settle" in caplog.text
    cold = solve_discrete(disc, warm_start=None)
    assert np.array_equal(result.u, cold.u) and result.certificate.ok


def test_linearised_error_recovers_a_planted_algebraic_error(small_case):
    """``u = u* + δ`` with δ on the free nodes: ``linearised_error`` returns δ and its energy
    ``(δᵀAδ)^{1/2}``; the exact solution itself has an algebraic error at round-off."""
    from signorini.solvers.algebraic_error import linearised_error

    disc, res = small_case
    A, b, B = disc.A, disc.b, disc.boundary
    free = np.setdiff1d(np.arange(b.size), B)  # interior nodes: u_B and the contact set unchanged
    delta = np.zeros_like(res.u)
    delta[free] = 1e-6 * np.abs(res.u).max() * np.random.default_rng(5).uniform(-1.0, 1.0, free.size)
    lam = res.lam + np.where(np.isin(B, res.active), (A @ delta)[B], 0.0)  # λ absorbs the contact rows only
    got = linearised_error(A, b, B, res.u + delta, lam, res.active)
    assert np.abs(got.delta - delta).max() <= 1e-6 * np.abs(delta).max()
    assert got.energy == pytest.approx(np.sqrt(delta @ (A @ delta)), rel=1e-6)
    exact = linearised_error(A, b, B, res.u, res.lam, res.active)
    assert np.abs(exact.delta).max() <= 1e-12 * np.abs(res.u).max()
    assert np.all(exact.delta[res.active] == 0.0)
    summary = exact.summary(res.u)
    assert set(summary) == {"energy", "max", "relative_max"} and summary["relative_max"] < 1e-12


def test_the_multigrid_correction_agrees_with_the_factorised_one(small_case):
    """The large meshes' route of the algebraic error (CG with the multigrid hierarchy) gives the
    planted error to the accuracy an estimate needs, with the contact set's nodes untouched."""
    from signorini.solvers.algebraic_error import ESTIMATE_RTOL, linearised_error

    disc, res = small_case
    A, b, B = disc.A, disc.b, disc.boundary
    free = np.setdiff1d(np.arange(b.size), B)
    delta = np.zeros_like(res.u)
    delta[free] = 1e-6 * np.abs(res.u).max() * np.random.default_rng(7).uniform(-1.0, 1.0, free.size)
    lam = res.lam + np.where(np.isin(B, res.active), (A @ delta)[B], 0.0)
    direct = linearised_error(A, b, B, res.u + delta, lam, res.active, "active_set")
    multigrid = linearised_error(A, b, B, res.u + delta, lam, res.active, "multigrid")
    error = multigrid.delta - direct.delta
    assert np.sqrt(error @ (A @ error)) <= 10 * ESTIMATE_RTOL * direct.energy
    assert multigrid.energy == pytest.approx(direct.energy, rel=10 * ESTIMATE_RTOL)
    assert np.all(multigrid.delta[res.active] == 0.0)
