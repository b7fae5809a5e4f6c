"""The options each solver route accepts, known before any job runs.

A configuration's solver options (a scene's ``solver_options``, a work-precision configuration's
``options``, an atlas column's ``options``) are checked at parse time, every Snakemake call, so
nothing here imports a solver: the routes' own options are declared in ``signorini.solvers.routes``
(tied to their signatures by its tests), Clarabel's settings are read from its extension (cheap),
and OSQP's and SCS's from the tables below (importing OSQP pulls in ``scipy.sparse``, which is not;
SCS names its settings nowhere but in its documentation; the costs:
docs/evidence/design-measurements.md#solver-options-without-imports).
``tests/pipeline/test_solver_options.py`` checks both tables against the installed packages.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

from signorini.solvers import routes
from signorini.solvers.routes import Option

# OSQP 1.x settings (osqp.ext_builtin.OSQPSettings); the flags are integers there, true/false is fine
OSQP_SETTINGS: dict[str, type] = {
    **dict.fromkeys(
        ("adaptive_rho", "adaptive_rho_interval", "cg_max_iter", "cg_tol_reduction", "check_dualgap"), int
    ),
    **dict.fromkeys(("check_termination", "device", "max_iter", "polish_refine_iter", "polishing"), int),
    **dict.fromkeys(("rho_is_vec", "scaled_termination", "scaling", "verbose", "warm_starting"), int),
    **dict.fromkeys(("adaptive_rho_fraction", "adaptive_rho_tolerance", "alpha", "cg_tol_fraction"), float),
    **dict.fromkeys(("delta", "eps_abs", "eps_dual_inf", "eps_prim_inf", "eps_rel", "rho", "sigma"), float),
    "time_limit": float,
    "cg_precond": object,  # enumerations of the extension
    "linsys_solver": object,
}
# SCS 3.3 settings (https://www.cvxgrp.org/scs/api/settings.html), and the ones cvxpy translates
# (eps, use_indirect -> linear_solver)
SCS_SETTINGS: dict[str, type] = {
    **dict.fromkeys(("max_iters", "acceleration_lookback", "acceleration_interval"), int),
    **dict.fromkeys(("eps_abs", "eps_rel", "eps_infeas", "alpha", "rho_x", "scale", "time_limit_secs"), float),
    **dict.fromkeys(("adaptive_scale", "normalize", "verbose"), bool),
    **dict.fromkeys(("write_data_filename", "log_csv_filename", "linear_solver"), str),
}
SCS_VIA_CVXPY: dict[str, type] = {"eps": float, "use_indirect": bool}
# keywords of cvxpy's Problem.solve itself, taken by every QP solver
CVXPY_SOLVE: dict[str, type] = {"verbose": bool, "ignore_dpp": bool, "enforce_dpp": bool, "canon_backend": str}


# the values a solver can use, beyond their type (``value_problem``): the names of the tolerances
# (kkt_tol, tol, inner_rtol, eps_abs, tol_gap_rel, iterative_refinement_reltol, ...) of every route
TOLERANCE = re.compile(r"(^|_)((r|abs|rel)?tol|eps)(_|$)")
# the caps of the iteration that is the solve (0 lets it take no step: our routes stop with
# "not converged", OSQP and SCS refuse it, Clarabel returns at once), and the counts of optional
# refinement steps (equilibrate_max_iter, polish_refine_iter, ...), where 0 switches them off
ITERATION_CAPS = frozenset({"max_iter", "max_iters", "max_cg_iter", "cg_max_iter"})
STEP_COUNT = re.compile(r"_iters?$")
TIME_LIMIT = re.compile(r"(^|_)time_limit")
FINITE_TIME_LIMITS = frozenset({"time_limit_secs"})  # SCS: "a nonnegative finite number"
# (finer, coarser): multigrid_solve's final solves are at least as accurate as its inner ones
ORDERED_TOLERANCES = (("tol", "inner_rtol"),)


def exact_routes() -> tuple[str, ...]:
    """The names of the certified active-set routes (``signorini.solvers.routes.EXACT_SOLVERS``)."""
    return routes.EXACT_SOLVERS


def _clarabel_settings() -> dict[str, type]:
    import clarabel

    settings = clarabel.DefaultSettings()
    return {
        name: type(getattr(settings, name))
        for name in dir(settings)
        if not name.startswith("_") and not callable(getattr(settings, name))
    }


def qp_settings(qp_solver: str) -> dict[str, type] | None:
    """The settings cvxpy passes on to ``qp_solver`` (None: not known here, not checked)."""
    solver = qp_solver.upper()
    if solver == "CLARABEL":
        return _clarabel_settings()
    return {"OSQP": {**OSQP_SETTINGS, "polish": int}, "SCS": {**SCS_SETTINGS, **SCS_VIA_CVXPY}}.get(solver)


def route_options(route: str) -> tuple[str, dict[str, Option] | None]:
    """The function a solver route reaches and the options it accepts (None: not checked): the
    scene's solver names (``signorini.solvers.routes``: a route, an alias, ``auto``, ``cvxpy_<QP>``)
    and a work-precision configuration's (an exact route or the QP solver's name, e.g. ``OSQP``).
    ``auto`` takes the options both exact routes accept (it picks one by the mesh's size)."""
    name = routes.canonical(route)
    if name == routes.AUTO:
        direct, multigrid = routes.DIRECT, routes.MULTIGRID
        common = {k: v for k, v in direct.options.items() if k in multigrid.options}
        return f"{direct.function} and {multigrid.function}", common
    if name in routes.ROUTES and routes.ROUTES[name].qp_parameter is None:
        return routes.ROUTES[name].function, dict(routes.ROUTES[name].options)
    qp = route.removeprefix(f"{routes.CVXPY.name}_")
    function = f"{routes.CVXPY.function}/{qp.upper()}"
    settings = qp_settings(qp)
    if settings is None:
        return function, None
    return function, {**routes.CVXPY.options, **{k: Option(t) for k, t in {**CVXPY_SOLVE, **settings}.items()}}


def value_problem(key: str, value: object, kind: type | None) -> str | None:
    """What a solver cannot use in ``value`` of the option ``key`` (of type ``kind``), in words
    after the value, or None: NaN anywhere; a tolerance that is not a finite number > 0 (0 or less
    is never met, inf or NaN certify anything); an iteration cap below 1, a count of refinement
    steps below 0; a time limit that is not > 0 (or not finite, where the solver refuses inf)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if kind is float and TOLERANCE.search(key) and not (math.isfinite(value) and value > 0):
        return "is not allowed; a tolerance is a finite number > 0 (e.g. 1e-8)"
    if math.isnan(value):
        return "is not a number; give a number"
    if kind is int and key in ITERATION_CAPS and value < 1:
        return "is not allowed; an iteration cap is at least 1 (with less the solver stops before its first step)"
    if kind is int and STEP_COUNT.search(key) and value < 0:
        return "is not allowed; a number of refinement steps is at least 0 (0 switches them off)"
    if kind is float and TIME_LIMIT.search(key):
        finite = key in FINITE_TIME_LIMITS
        if not value > 0 or (finite and math.isinf(value)):
            return f"is not allowed; a time limit is a{' finite' if finite else ''} number of seconds > 0"
    return None


def _order_problem(where: str, options: Mapping, accepted: Mapping[str, Option]) -> str | None:
    """A finer tolerance set above its coarser one (``ORDERED_TOLERANCES``, with the defaults)."""
    for finer, coarser in ORDERED_TOLERANCES:
        if finer not in accepted or coarser not in accepted or not ({finer, coarser} & set(options)):
            continue
        fine, coarse = options.get(finer, accepted[finer].default), options.get(coarser, accepted[coarser].default)
        if isinstance(fine, (int, float)) and isinstance(coarse, (int, float)) and fine > coarse:
            key = finer if finer in options else coarser
            return (
                f"{where}.{key}: {finer} = {fine!r} is larger than {coarser} = {coarse!r}; the final solves are at "
                f"least as accurate as the inner ones ({finer} ≤ {coarser})"
            )
    return None


def check_options(where: str, route: str, options: Mapping) -> str | None:
    """The first problem with ``options`` of a solver ``route`` (an unknown name, a value of the
    wrong type, or one the solver cannot use: ``value_problem``, ``ORDERED_TOLERANCES``), as a
    message naming the field under ``where``, or None."""
    if route == routes.CVXPY.name:  # the QP solver is an option itself
        options = dict(options)
        route = f"{routes.CVXPY.name}_{options.pop(routes.QP_OPTION, routes.DEFAULT_QP_SOLVER)}"
    function, accepted = route_options(route)
    for key, value in (options.items() if accepted is not None else ()):
        if key not in accepted:
            return f"{where}.{key}: not an option of {function}; choose from {sorted(accepted)}"
        kind, nullable = accepted[key].kind, accepted[key].nullable
        if kind is None or kind is object or (value is None and nullable):
            continue
        ok = (int, float) if kind is float else kind
        if not isinstance(value, ok) or (kind in (float, str) and isinstance(value, bool)):
            return f"{where}.{key}: {'null' if value is None else repr(value)} is not of type {kind.__name__}"
        if (problem := value_problem(key, value, kind)) is not None:
            return f"{where}.{key}: {value!r} {problem}"
    return _order_problem(where, options, accepted) if accepted is not None else None
