"""The same QP through cvxpy, with any installed QP-capable solver by name.

``min ½ uᵀAu - bᵀu  s.t.  u_B ≥ 0``; the multiplier is the dual value of the
bound constraint.  ``psd_wrap`` skips cvxpy's eigenvalue PSD check, which is
prohibitive for large sparse ``A`` (``check_qp_data`` has certified A symmetric
positive semidefinite before).

Scaling.  The QP solvers stop on *absolute* tolerances (OSQP's ``eps_abs``, SCS's
``eps_abs``, Clarabel's ``tol_gap_abs``/``tol_feas`` against unscaled norms), so the
same data multiplied by 10⁻¹² is "solved" by ``u = 0`` and by 10¹² never.  With
``normalize=True`` the solver sees ``(A/α, b/β)``, whose KKT point is
``(u', λ') = (α u/β, λ/β)`` (divide ``A u - b = λ`` by ``β`` and substitute ``u = (β/α) u'``);
the answer is mapped back.  ``α = max_i A_ii`` and ``β = α ‖u_D‖∞`` with ``u_D`` the solution
with ``u_B = 0`` (``A_II u_D = b_I`` on the unconstrained indices ``I``, one sparse
factorisation), an estimate of ``‖u‖∞`` that is linear in the data: ``u' = O(1)`` and ``A'``
has unit diagonal.  Every tolerance is then relative, and the result is invariant under
``b → s b`` and ``A → s A`` up to round-off (``stability`` atlas, scaling cases).  (``β = ‖b‖∞``
is not enough: for ``f ≡ 1`` at N = 201 it gives ``u' ≈ 2·10⁵`` against ``λ_min(A') ≈ 6·10⁻⁶``,
and Clarabel and SCS declare the QP unbounded.)  Off by default so that the tolerance
sweeps of ``benchmarks/qp_tolerance.py`` keep their meaning.
"""

from __future__ import annotations

import importlib.util
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


# cvxpy's solvers that accept a QP with bound constraints (its QP solvers, and the conic solvers that
# take quadratic objectives), each with the modules its interface imports (``import_solver``)
QP_SOLVER_MODULES: dict[str, tuple[str, ...]] = {
    "CLARABEL": ("clarabel",),
    "COPT": ("coptpy",),
    "CPLEX": ("cplex",),
    "DAQP": ("daqp",),
    "GUROBI": ("gurobipy",),
    "HIGHS": ("highspy",),
    "KNITRO": ("knitro",),
    "MPAX": ("jax", "mpax"),
    "OSQP": ("osqp",),
    "PIQP": ("piqp",),
    "PROXQP": ("proxsuite",),
    "QPALM": ("qpalm",),
    "SCS": ("scs",),
    "XPRESS": ("xpress",),
}


def installed_qp_solvers() -> list[str]:
    """cvxpy's installed solvers that accept a QP with bound constraints: those whose modules are
    installed (``QP_SOLVER_MODULES``), found without importing cvxpy, which the workflow would
    otherwise import while it plans the work-precision study."""
    found = importlib.util.find_spec
    return sorted(s for s, modules in QP_SOLVER_MODULES.items() if all(found(m) is not None for m in modules))


def data_scales(A: sp.csr_matrix, b: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    """``(α, β)`` of ``normalize=True`` (module docstring): ``α = max A_ii``, ``β = α ‖u_D‖∞``;
    ``β = ‖b‖∞`` when ``u_D`` is not available (no unconstrained index, ``u_D = 0``), 1 for ``b = 0``."""
    from signorini.solvers.linalg import factorize

    alpha = float(A.diagonal().max())
    free = np.ones(b.size, dtype=bool)
    free[B] = False
    beta = 0.0
    if free.any() and np.any(b[free]):
        A_II = A[free][:, free]
        # A_II is a principal block of the PSD A; the shift of check_psd keeps it definite
        u_D = factorize(A_II + 1e-8 * sp.diags(A_II.diagonal()))(b[free])
        beta = alpha * float(np.abs(u_D).max())
    if not (np.isfinite(beta) and beta > 0.0):
        beta = float(np.abs(b).max(initial=0.0))
    return alpha, beta if beta > 0.0 else 1.0  # b = 0: the solution is u = 0 whatever the scale


def solver_settings(solver: str, tol: float | None, options: dict) -> dict:
    """The options cvxpy passes to ``solver`` (upper case): ``tol`` set as all of its
    tolerances, OSQP's polishing on by default, HiGHS without its QP regularisation."""
    options = dict(options)
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
    return options


def cvxpy_solve(
    A: sp.spmatrix,
    b: np.ndarray,
    constrained: np.ndarray,
    solver: str = "CLARABEL",
    tol: float | None = None,
    kkt_tol: float = 1e-6,
    check: bool = True,
    normalize: bool = False,
    **solver_options,
) -> SolveResult:
    """Solve the QP with cvxpy's ``solver``; ``tol`` sets all of the solver's tolerances,
    ``normalize`` makes them relative to the data (see the module docstring).

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
    options = solver_settings(solver, tol, solver_options)
    t0 = time.perf_counter()
    # (A, b) = (α A', β b'): the solver sees (A', b'), u = (β/α) u', λ = β λ' (module docstring)
    alpha, beta = data_scales(A, b, B) if normalize else (1.0, 1.0)
    Aq, bq = (A / alpha, b / beta) if normalize else (A, b)
    u = cp.Variable(b.size)
    bound = u[B] >= 0
    prob = cp.Problem(cp.Minimize(0.5 * cp.quad_form(u, cp.psd_wrap(Aq)) - bq @ u), [bound])
    try:
        prob.solve(solver=solver, **options)
    except cp.error.SolverError as err:
        raise NotConvergedError(f"cvxpy/{solver} failed: {err}") from err
    wall = time.perf_counter() - t0
    if prob.status != cp.OPTIMAL or u.value is None:
        raise NotConvergedError(f"cvxpy/{solver} returned status {prob.status!r}", status=str(prob.status))
    x = (beta / alpha) * np.asarray(u.value, dtype=float)
    lam = beta * np.asarray(bound.dual_value, dtype=float).ravel()
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
            "normalize": bool(normalize),
            "scales": [alpha, beta],
        },
    )
    if check and not cert.ok:
        raise KKTError(f"cvxpy/{solver} solution fails its KKT certificate", cert)
    return result
