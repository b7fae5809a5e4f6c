"""The same QP through cvxpy, with any installed QP-capable solver by name.

``min ½ uᵀAu - bᵀu  s.t.  u_B ≥ 0``; the multiplier is the dual value of the
bound constraint.  ``psd_wrap`` skips cvxpy's eigenvalue PSD check, which is
prohibitive for large sparse ``A`` (A is SPD by construction).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from signorini.solvers.certificate import KKTError, NotConvergedError, check_qp_data, kkt_certificate
from signorini.solvers.result import SolveResult

# solver name -> (option name for a tolerance, the solver's default for it)
TOLERANCE_OPTIONS: dict[str, tuple[tuple[str, ...], float]] = {
    "CLARABEL": (("tol_gap_abs", "tol_gap_rel", "tol_feas", "tol_ktratio"), 1e-8),
    "OSQP": (("eps_abs", "eps_rel"), 1e-3),
    "HIGHS": (("primal_feasibility_tolerance", "dual_feasibility_tolerance"), 1e-7),
    "SCS": (("eps_abs", "eps_rel"), 1e-4),
    "PIQP": (("eps_abs", "eps_rel"), 1e-8),
    "PROXQP": (("eps_abs",), 1e-9),
    "ECOS": (("abstol", "reltol", "feastol"), 1e-8),
}


def installed_qp_solvers() -> list[str]:
    """cvxpy's installed solvers that accept a QP with bound constraints."""
    import cvxpy as cp
    from cvxpy.reductions.solvers.defines import QP_SOLVERS

    qp = set(QP_SOLVERS) | {"CLARABEL", "SCS"}  # conic solvers that take quadratic objectives
    return sorted(s for s in cp.installed_solvers() if s in qp)


def cvxpy_solve(
    A: sp.spmatrix,
    b: np.ndarray,
    constrained: np.ndarray,
    solver: str = "CLARABEL",
    tol: float | None = None,
    kkt_tol: float = 1e-6,
    check: bool = True,
    **solver_options,
) -> SolveResult:
    """Solve the QP with cvxpy's ``solver``; ``tol`` sets all of the solver's tolerances.

    Raises ``NotConvergedError`` for a status other than optimal and ``KKTError``
    when ``check`` is set and the certificate exceeds ``kkt_tol``.
    """
    import cvxpy as cp

    solver = solver.upper()
    available = installed_qp_solvers()
    if solver not in available:
        raise ValueError(f"unknown or uninstalled cvxpy QP solver {solver!r}; installed: {available}")
    A = sp.csr_matrix(A)
    b = np.asarray(b, dtype=float)
    B = np.asarray(constrained, dtype=np.int64)
    check_qp_data(A, b, B)
    options = dict(solver_options)
    if tol is not None:
        names, _ = TOLERANCE_OPTIONS.get(solver, ((), None))
        if not names:
            raise ValueError(f"no tolerance mapping for solver {solver!r}; pass its options explicitly")
        options.update({name: tol for name in names})
    if solver == "OSQP":
        options.setdefault("polishing", options.pop("polish", True))
    if solver == "HIGHS":
        # HiGHS regularises QPs by default, which biases the answer by ~1e-7
        options.setdefault("qp_regularization_value", 0.0)
        for name in TOLERANCE_OPTIONS["HIGHS"][0]:
            if name in options:
                options[name] = max(float(options[name]), 1e-10)  # HiGHS rejects smaller values

    t0 = time.perf_counter()
    u = cp.Variable(b.size)
    bound = u[B] >= 0
    prob = cp.Problem(cp.Minimize(0.5 * cp.quad_form(u, cp.psd_wrap(A)) - b @ u), [bound])
    try:
        prob.solve(solver=solver, **options)
    except cp.error.SolverError as err:
        raise NotConvergedError(f"cvxpy/{solver} failed: {err}") from err
    wall = time.perf_counter() - t0
    if prob.status != cp.OPTIMAL or u.value is None:
        raise NotConvergedError(f"cvxpy/{solver} returned status {prob.status!r}")
    x = np.asarray(u.value, dtype=float)
    lam = np.asarray(bound.dual_value, dtype=float).ravel()
    stats = prob.solver_stats
    iterations = int(stats.num_iters) if stats.num_iters is not None else -1
    cert = kkt_certificate(A, b, B, x, lam, kkt_tol)
    # contact set: nodes the solver left at (relative) round-off distance from zero
    active = B[x[B] <= 1e-8 * max(np.abs(x).max(initial=0.0), np.finfo(float).tiny)]
    result = SolveResult(
        u=x,
        lam=lam,
        active=active,
        iterations=iterations,
        wall_time_s=wall,
        certificate=cert,
        solver=f"cvxpy_{solver.lower()}",
        info={
            "status": prob.status,
            "solve_time_s": float(stats.solve_time or np.nan),
            "options": {k: str(v) for k, v in options.items()},
        },
    )
    if check and not cert.ok:
        raise KKTError(f"cvxpy/{solver} solution fails its KKT certificate", cert)
    return result
