"""Numerical stability atlas: the discretisation, the solvers and the norms on extreme cases.

Every case is a config entry of the scene ``stability`` (``workflow/config.yaml``, block
``atlas``); every case is solved by every configured solver, and each (case, solver) gets a
status, the reason of a failure, iterations, wall time, the relative KKT residuals
(``solvers.certificate``), the errors in the paper's norms relative to ``‖u‖`` in the same
norm (absolute where ``‖u‖ = 0``), and a flag for any NaN/Inf.  The cases and what the
mathematics predicts for them:

``scaling``
    ``u ↦ s u`` (amplitude ``A``).  ``(S_h)`` is positively homogeneous, ``u_h(s f) = s u_h(f)``
    with the same contact set, so every relative quantity must agree to round-off.  This
    holds for a solver only if all its thresholds are relative: the active-set method's are
    (hysteresis ``1e-13 max(|λ|, |b|)``, ``1e-13 ‖u‖``, refinement below ``4 ε |A||u|``); the QP solvers
    behind cvxpy stop on absolute tolerances unless ``normalize=True``
    (``solvers.cvxpy_qp``).
``reaction``
    ``-Δu + c u = f`` with ``f`` derived for the same ``u``.  The matrix ``A = K + c M``
    (no Dirichlet part: ``K 1 = 0``) has ``λ_min(A) ≈ c |Ω| / n`` for small ``c``: nearly
    semicoercive, ``κ₂(A) → ∞`` as ``c → 0``; the active-set method factorises only the
    block of the free nodes ``A_FF``, which the Dirichlet condition on the contact set keeps
    definite.  For ``c h² ≫ 1`` the matrix is mass-dominated, no M-matrix (positive
    off-diagonal entries), the discrete maximum principle fails.  ``κ₂`` is estimated from
    ARPACK's extreme eigenvalues (``scipy.sparse.linalg.eigsh``: Lanczos for ``λ_max``,
    shift-invert at ``σ = -1e-10 λ_max`` for ``λ_min``) on meshes up to ``cond_max_dofs``.
``mesh``
    ``N = 2`` and ``3`` (the free boundary segment ``(x0 - R, x0)`` holds zero or one node), even
    ``N`` (the free point ``(x0, 0)`` is a node), the other diagonal, interior nodes jittered by
    up to 20 % of ``h``, large ``N``.  ``solve_discrete``'s cascade interpolates the solution
    of an *unjittered* coarse mesh at the fine nodes; for a jittered fine mesh this is still
    the exact evaluation of the coarse P1 function at those points (``interpolate_fk`` locates
    arbitrary points), so the warm start stays a valid guess, and the certificate decides;
    the atlas checks it against a cold start (solver ``active_set_cold``).
``degenerate``
    ``f ≡ 0`` (``u = 0``; every boundary point biactive), a small support (``u = ∂_ν u = 0`` on
    most of ∂Ω), full contact (``f ≤ 0``) and no contact (``f ≡ 1``, ``c = 1``: ``u ≡ 1``), see
    ``problem.ConstantProblem`` and ``problem.FullContactProblem``.
``bad_input``
    NaN/Inf data, a non-symmetric or indefinite matrix, an empty constraint set: every solver
    must stop with a clear error (``BadInputError``, ``ProblemParameterError``), not hang and
    not return a number.

Isolation: each solve runs in a forked child process with a hard time limit, so a hang or a
crash inside a solver library becomes ``failed`` with the reason and never stops the scene.
This module is the stage ``stability_case``; the cases come from ``atlas``, the table, report
and figure are rendered by ``table``, ``report`` and ``figures``.
"""

from __future__ import annotations

import logging
import math
import multiprocessing
import os
import time
import traceback
import warnings
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from signorini.studies.stability.atlas import Atlas, Case, SolverSpec

log = logging.getLogger(__name__)

# exception classes that count as the clear error a bad input must produce
INPUT_ERRORS = ("BadInputError", "ProblemParameterError")
ZERO_NORM_RTOL = 1e-10  # ‖u‖ in a norm ≤ this · max over norms: u counts as 0 there (absolute error)


# --- building a case ---------------------------------------------------------------------------


def build_case(case: Case):
    """Mesh, assemble and (for bad-input cases) corrupt the QP of a case: a ``DiscreteProblem``.

    ``nan_parameter`` raises ``ProblemParameterError`` here, as it would in any caller.
    """
    from signorini.fem.assembly import assemble, p1_basis, system_matrix
    from signorini.fem.discrete import DiscreteProblem
    from signorini.fem.mesh import boundary_nodes, friedrichs_keller
    from signorini.fem.mesh_families import mesh_from_spec
    from signorini.fem.problem import make_problem

    params = dict(case.problem)
    if case.corrupt == "nan_parameter":
        params["A"] = math.nan
    problem = make_problem(params)
    if case.mesh:
        mesh = mesh_from_spec(case.N, case.mesh, case.diagonal)
    else:  # the paper's mesh, jittered by the case
        mesh = friedrichs_keller(case.N, case.diagonal, case.jitter, case.seed)
    A, b = assemble(mesh, problem)
    B = boundary_nodes(mesh)
    n = b.size
    if case.corrupt == "nan_b":
        b = b.copy()
        b[n // 2] = math.nan
    elif case.corrupt == "inf_A":
        A = A.tolil()
        A[n // 2, n // 2] = math.inf
        A = A.tocsr()
    elif case.corrupt == "non_spd":
        A = system_matrix(p1_basis(mesh, intorder=2), -1.0)
    elif case.corrupt == "nonsymmetric":
        A = A.copy()
        row = n // 2
        k = next(k for k in range(A.indptr[row], A.indptr[row + 1]) if A.indices[k] != row)
        A.data[k] *= 1.5
    elif case.corrupt == "empty_constraints":
        B = np.zeros(0, dtype=np.int64)
    return DiscreteProblem(problem, case.N, case.diagonal, mesh, A, b, B)


# --- running one solver in isolation -----------------------------------------------------------


def run_isolated(fn: Callable[[], object], timeout_s: float) -> tuple[str, object]:
    """Run ``fn()`` in a forked child with a hard time limit.

    Returns ``("ok", value)``, ``("error", "<ExceptionClass>: message")``, ``("timeout", text)``
    or ``("crash", text)`` (the child died without answering, e.g. a segfault).  The child
    inherits the parent's memory (fork), so large inputs are not copied.
    """
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)

    def child() -> None:
        try:
            payload = ("ok", fn())
        except BaseException as err:  # noqa: BLE001 - every failure is reported, none escapes
            log.debug("isolated call failed:\n%s", traceback.format_exc())
            payload = ("error", f"{type(err).__name__}: {err}")
        try:
            send.send(payload)
        except Exception as err:  # noqa: BLE001 - an unpicklable result is a failure too
            send.send(("error", f"{type(err).__name__}: result not transferable ({err})"))
        send.close()

    proc = ctx.Process(target=child, daemon=True)
    proc.start()
    send.close()
    try:
        if recv.poll(timeout_s):
            try:
                return recv.recv()
            except EOFError:
                proc.join(5)
                return "crash", f"solver process died (exit code {proc.exitcode})"
        return "timeout", f"no answer within the hard time limit of {timeout_s:g} s (process killed)"
    finally:
        recv.close()
        if proc.is_alive():
            proc.kill()
        proc.join(5)


def _solve_and_measure(disc, spec: SolverSpec, norms: Sequence[str], u_norms: Mapping[str, float]) -> dict:
    """Solve one case with one solver and measure everything (runs in the child process)."""
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.solve import solve_discrete
    from signorini.solvers import EXACT_SOLVERS, kkt_certificate

    options = dict(spec.options)
    if spec.solver in EXACT_SOLVERS:
        options.setdefault("kkt_tol", math.inf)  # classify here, with the solution in hand
    else:
        options.update(check=False, kkt_tol=spec.kkt_tol)
    fp_warnings: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with np.errstate(all="warn"):
            t0 = time.perf_counter()
            res = solve_discrete(disc, spec.solver, **options)
            t1 = time.perf_counter()
            cert = kkt_certificate(disc.A, disc.b, disc.boundary, res.u, res.lam, spec.kkt_tol)
            finite = bool(np.all(np.isfinite(res.u)) and np.all(np.isfinite(res.lam)))
            errors = evaluate_norms(disc.problem, disc.mesh, res.u, list(norms)) if finite else {}
            t2 = time.perf_counter()
    fp_warnings = sorted({str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)})
    relative = {n: u_norms[n] > ZERO_NORM_RTOL * max(u_norms.values(), default=0.0) for n in norms}
    out = {
        "iterations": int(res.iterations),
        "factorizations": int(res.info.get("factorizations", -1)),
        "solve_s": t1 - t0,
        "norms_s": t2 - t1,
        "n_active": int(res.active.size),
        "cert": cert.as_dict(),
        "finite": finite,
        "fp_warnings": fp_warnings,
        "errors": {n: (errors[n] / u_norms[n] if relative[n] else errors[n]) for n in errors},
        "relative": relative,
    }
    return {"row": out, "u": np.asarray(res.u), "active": np.sort(np.asarray(res.active))}


def classify(outcome: str, payload, spec: SolverSpec, case: Case) -> dict:
    """Status, reason and the measured fields of one (case, solver) from ``run_isolated``'s answer."""
    row: dict = {"status": "failed", "reason": "", "nan_inf": False}
    if outcome != "ok":
        row["reason"] = str(payload)
    else:
        m = payload["row"]
        cert = m["cert"]
        residuals = [cert[k] for k in ("stationarity", "primal", "dual", "complementarity")]
        errors = list(m["errors"].values())
        row["nan_inf"] = bool(
            not m["finite"]
            or not np.all(np.isfinite(residuals))
            or not np.all(np.isfinite(errors))
            or any(("invalid" in w or "overflow" in w or "divide" in w) for w in m["fp_warnings"])
        )
        row.update(
            iterations=m["iterations"],
            factorizations=m["factorizations"],
            solve_s=m["solve_s"],
            norms_s=m["norms_s"],
            n_active=m["n_active"],
            fp_warnings="; ".join(m["fp_warnings"]),
            **{f"kkt_{k}": cert[k] for k in ("stationarity", "primal", "dual", "complementarity", "worst")},
            kkt_threshold=cert["threshold"],
            errors_relative=all(m["relative"].values()),
            absolute_norms=" ".join(n for n, rel in m["relative"].items() if not rel),
            **{f"err_{n}": v for n, v in m["errors"].items()},
        )
        if not m["finite"]:
            row["reason"] = "NaN/Inf in the solution"
        elif cert["ok"]:
            row["status"] = "ok"
        else:
            row["status"] = "inaccurate"
            row["reason"] = f"KKT residual {cert['worst']:.1e} > {cert['threshold']:.0e}"
    clear_error = row["status"] == "failed" and row["reason"].split(":", 1)[0] in INPUT_ERRORS
    row["as_expected"] = clear_error if case.expect == "error" else row["status"] == "ok"
    return row


# --- condition numbers ---------------------------------------------------------------------------


def extreme_eigenvalues(A) -> tuple[float, float]:
    """``(λ_min, λ_max)`` of a symmetric positive (semi)definite sparse matrix by ARPACK:
    Lanczos for the largest, shift-invert at ``σ = -1e-10 λ_max`` for the smallest (``A - σI``
    is definite even for a singular ``A``; the shift costs an absolute error ~1e-18 λ_max)."""
    import scipy.sparse.linalg as spla

    n = A.shape[0]
    if n <= 200:
        w = np.linalg.eigvalsh(A.toarray())
        return float(w[0]), float(w[-1])
    lmax = float(spla.eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-8)[0])
    sigma = -1e-10 * lmax
    lmin = float(spla.eigsh(A, k=1, sigma=sigma, which="LM", return_eigenvectors=False, tol=1e-10)[0])
    return lmin, lmax


def condition_estimates(disc, active: np.ndarray | None) -> dict:
    """``κ₂(A)`` of the whole matrix and ``κ₂(A_FF)`` of its block on the free nodes (the
    complement of the exact solver's contact set: what the active-set method factorises)."""
    out: dict = {}
    lmin, lmax = extreme_eigenvalues(disc.A)
    out.update(lambda_min=lmin, lambda_max=lmax, cond_A=lmax / lmin if lmin > 0 else math.inf)
    if active is not None:
        free = np.ones(disc.b.size, dtype=bool)
        free[active] = False
        lmin_f, lmax_f = extreme_eigenvalues(disc.A[free][:, free])
        out.update(lambda_min_free=lmin_f, cond_free=lmax_f / lmin_f if lmin_f > 0 else math.inf)
    return out


# --- the case stage ----------------------------------------------------------------------------------


def run_case(atlas: Atlas, case: Case) -> tuple[dict, dict[str, np.ndarray]]:
    """All solvers on one case: ``({"case", "rows", "cond", ...}, {"u_<solver>", "active_<solver>"})``.

    Nothing raises: a failure to build the case fails every solver with that reason.
    """
    from signorini.fem.norms.conventional import evaluate_norms

    t0 = time.perf_counter()
    arrays: dict[str, np.ndarray] = {}
    rows: list[dict] = []
    info: dict = {"case": case.as_dict(), "expect": case.expect}
    try:
        disc = build_case(case)
        u_norms = evaluate_norms(disc.problem, disc.mesh, np.zeros(disc.b.size), list(atlas.norms))
        build_error = None
    except Exception as err:  # noqa: BLE001 - reported as the reason of every solver
        disc, u_norms, build_error = None, {}, f"{type(err).__name__}: {err}"
        log.info("case %s: building failed: %s", case.name, build_error)
    info["build_s"] = time.perf_counter() - t0
    info["u_norms"] = u_norms
    info["n_constrained"] = None if disc is None else int(disc.boundary.size)  # 4N on a Friedrichs–Keller mesh
    if any(atlas.solvers[label].solver.startswith("cvxpy") for label in case.solvers):
        from signorini.solvers import installed_qp_solvers

        # import cvxpy and its solver interfaces once, before the forks: each child would pay the import
        # again (docs/evidence/design-measurements.md#cvxpy-import-before-fork)
        installed_qp_solvers()
    for label in case.solvers:
        spec = atlas.solvers[label]
        t1 = time.perf_counter()
        if build_error is not None:
            outcome, payload = "error", build_error
        else:
            outcome, payload = run_isolated(
                lambda spec=spec: _solve_and_measure(disc, spec, atlas.norms, u_norms), atlas.timeout_s
            )
        row = {"solver": label, "route": spec.solver, **classify(outcome, payload, spec, case),
               "total_s": time.perf_counter() - t1}
        if outcome == "ok" and payload["row"]["finite"]:
            arrays[f"u_{label}"] = payload["u"]
            arrays[f"active_{label}"] = payload["active"]
        log.info("case %s, %s: %s %s", case.name, label, row["status"], row["reason"])
        rows.append(row)
    # distance of every solution to the exact solver's (active_set) of the same case
    # (relative to ‖u_exact‖∞; absolute when u_exact = 0)
    exact = arrays.get("u_active_set")
    for row in rows:
        u = arrays.get(f"u_{row['solver']}")
        if exact is not None and u is not None:
            scale = np.abs(exact).max(initial=0.0)
            row["diff_to_active_set"] = float(np.abs(u - exact).max(initial=0.0) / (scale if scale > 0 else 1.0))
            row["same_contact_as_active_set"] = bool(
                np.array_equal(arrays[f"active_{row['solver']}"], arrays["active_active_set"])
            )
    info["rows"] = rows
    info["cond"] = {}
    if disc is not None and disc.b.size <= atlas.cond_max_dofs and case.corrupt is None:
        outcome, payload = run_isolated(
            lambda: condition_estimates(disc, arrays.get("active_active_set")), atlas.timeout_s
        )
        info["cond"] = payload if outcome == "ok" else {"error": str(payload)}
    info["wall_s"] = time.perf_counter() - t0
    return info, arrays


def case_stage(job: Mapping, out_json: str | os.PathLike, out_npz: str | os.PathLike) -> dict:
    """Stage of the rule ``stability_case``: run one atlas case (``Atlas.job``), write its JSON
    (rows, condition estimates) and the solutions (``u_<solver>``, ``active_<solver>``)."""
    from signorini.pipeline.artifacts import save_json, save_npz

    atlas = Atlas.from_job(job)
    case = atlas.cases[0]
    info, arrays = run_case(atlas, case)
    save_npz(out_npz, **arrays)
    save_json(out_json, info)
    return info
