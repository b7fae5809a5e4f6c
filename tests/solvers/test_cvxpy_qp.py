"""Every installed cvxpy QP solver (``signorini.solvers.cvxpy_qp``) as an independent cross-check
of the exact solution, its named errors, and the normalised data of ``normalize=True``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import check_kkt_independently, rel_max_diff
from helpers import rel_max_diff as rel

from signorini.fem.discrete import build
from signorini.fem.problem import Problem
from signorini.solvers import KKTError, NotConvergedError, solve
from signorini.solvers.cvxpy_qp import (
    TOLERANCE_OPTIONS,
    cvxpy_solve,
    data_scales,
    installed_qp_solvers,
    solver_settings,
)


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


# ---------------------------------------------------------------------------------
# cvxpy cross-checks
# ---------------------------------------------------------------------------------


def test_installed_qp_solvers():
    assert installed_qp_solvers() == QP_SOLVER_NAMES
    assert "CLARABEL" in QP_SOLVER_NAMES and "OSQP" in QP_SOLVER_NAMES


def test_the_installed_qp_solvers_are_found_from_cvxpys_list_without_importing_it(monkeypatch):
    """Every QP-capable solver of cvxpy has its modules listed; a solver one of whose modules is
    missing is not installed; and finding them imports no cvxpy (the workflow asks while it plans)."""
    import importlib.util
    import subprocess
    import sys

    from cvxpy.reductions.solvers.defines import QP_SOLVERS

    from signorini.solvers import cvxpy_qp

    assert set(cvxpy_qp.QP_SOLVER_MODULES) == set(QP_SOLVERS) | {"CLARABEL", "SCS"}
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "osqp" else real(name, *a))
    assert installed_qp_solvers() == [s for s in QP_SOLVER_NAMES if s != "OSQP"]
    code = "import sys; from signorini.solvers import installed_qp_solvers as f; f(); print('cvxpy' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"


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


def test_normalized_cvxpy_is_scale_invariant_and_raw_is_not():
    """With ``normalize=True`` OSQP's answer scales with the data; as shipped (absolute
    tolerances) it does not converge for A = 1e12 (or returns a non-KKT point)."""
    N = 11
    ref = cvxpy_solve(*_qp(build(Problem(A=1.0), N)), solver="OSQP", tol=1e-8, normalize=True)
    for A in (1e-12, 1e12):
        res = cvxpy_solve(*_qp(build(Problem(A=A), N)), solver="OSQP", tol=1e-8, normalize=True)
        assert res.certificate.ok and rel(res.u / A, ref.u) <= 1e-8
        np.testing.assert_array_equal(res.active, ref.active)
    try:
        raw = cvxpy_solve(*_qp(build(Problem(A=1e12), N)), solver="OSQP", tol=1e-8, check=False)
    except NotConvergedError:
        return
    assert not raw.certificate.ok


def _qp(disc):
    return disc.A, disc.b, disc.boundary


# ---------------------------------------------------------------------------------
# the data of normalize=True and the solvers' settings
# ---------------------------------------------------------------------------------


def test_the_scales_of_the_normalised_data_follow_the_data(cache):
    """α = max A_ii and β = α ‖u_D‖∞ (u_D: the solution with the boundary clamped to 0): scaling A
    by s and b by t scales α by s and β by t; b = 0 gives β = 1."""
    disc = cache.discrete({}, 11)
    alpha, beta = data_scales(disc.A, disc.b, disc.boundary)
    assert alpha == disc.A.diagonal().max() and beta > 0
    alpha2, beta2 = data_scales(1e6 * disc.A, 1e-3 * disc.b, disc.boundary)
    assert alpha2 == pytest.approx(1e6 * alpha, rel=1e-14) and beta2 == pytest.approx(1e-3 * beta, rel=1e-6)
    assert data_scales(disc.A, 0 * disc.b, disc.boundary) == (alpha, 1.0)


def test_a_tolerance_sets_every_tolerance_of_a_solver():
    osqp = solver_settings("OSQP", 1e-9, {})
    assert all(osqp[name] == 1e-9 for name in TOLERANCE_OPTIONS["OSQP"][0]) and osqp["polishing"] is True
    assert solver_settings("OSQP", None, {"polish": False}) == {"polishing": False}
    highs = solver_settings("HIGHS", 1e-12, {})
    assert highs["qp_regularization_value"] == 0.0
    assert all(highs[name] == 1e-10 for name in TOLERANCE_OPTIONS["HIGHS"][0])  # HiGHS's smallest
    with pytest.raises(ValueError, match="no tolerance mapping"):
        solver_settings("NOSUCHSOLVER", 1e-8, {})
