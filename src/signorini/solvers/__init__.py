"""Solvers for the discrete Signorini QP behind one interface.

``solve(name, A, b, constrained, **options)`` with ``name`` a route of ``solvers.routes``:
``direct`` (exact, certified: the active-set iteration with each Newton system solved by a sparse
factorisation; ``active_set`` is its earlier name), ``multigrid`` (exact, certified, the same
iteration with multigrid-preconditioned CG: O(n)), ``auto`` (``multigrid`` from
``MULTIGRID_FROM_UNKNOWNS`` unknowns on, ``direct`` below) or ``cvxpy`` (any installed cvxpy QP
solver chosen by the ``qp_solver`` option); a shorthand ``cvxpy_clarabel``, ``cvxpy_osqp``, …
selects the QP solver in the name.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from signorini.solvers.routes import (
    DEFAULT_QP_SOLVER,
    EXACT_SOLVERS,
    MULTIGRID_FROM_UNKNOWNS,
    QP_OPTION,
    ROUTES,
    SOLVERS,
    exact_route,
    resolve,
)

if TYPE_CHECKING:
    from collections.abc import Callable

    import numpy as np
    import scipy.sparse as sp

    from signorini.solvers.result import SolveResult


def route_functions() -> dict[str, Callable[..., SolveResult]]:
    """{route name: its function} (``solvers.routes.ROUTES``), imported here: a solve job's code
    inputs are the modules its imports name."""
    from signorini.solvers.active_set import active_set_solve
    from signorini.solvers.cvxpy_qp import cvxpy_solve
    from signorini.solvers.multigrid import multigrid_solve

    functions = {f.__name__: f for f in (active_set_solve, cvxpy_solve, multigrid_solve)}
    return {name: functions[route.function] for name, route in ROUTES.items()}


def solve(name: str, A: sp.spmatrix, b: np.ndarray, constrained: np.ndarray, **options) -> SolveResult:
    """Dispatch to a solver route by name (``solvers.routes.resolve``); unknown names raise
    ``ValueError``.  A route that takes the QP solver by name gets it from the name or the option
    ``qp_solver`` (default Clarabel), and no warm start."""
    route, qp_solver = resolve(name, len(b))
    if route.qp_parameter is not None:
        options.pop("warm_start", None)
        options[route.qp_parameter] = qp_solver or options.pop(QP_OPTION, DEFAULT_QP_SOLVER)
    return route_functions()[route.name](A, b, constrained, **options)


def __getattr__(name: str) -> Any:
    """The routes' functions and the certificate's names, imported when first asked for: the names
    above (``solvers.routes``) serve the workflow's config checks, which must not pay for numpy,
    scipy and cvxpy while Snakemake parses the workflow."""
    if name in ("BadInputError", "Certificate", "KKTError", "NotConvergedError", "kkt_certificate"):
        from signorini.solvers import certificate as module
    elif name == "SolveResult":
        from signorini.solvers import result as module
    elif name == "active_set_solve":
        from signorini.solvers import active_set as module
    elif name in ("cvxpy_solve", "installed_qp_solvers"):
        from signorini.solvers import cvxpy_qp as module
    elif name == "multigrid_solve":
        from signorini.solvers import multigrid as module
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(module, name)


__all__ = [
    "EXACT_SOLVERS",
    "MULTIGRID_FROM_UNKNOWNS",
    "SOLVERS",
    "BadInputError",
    "Certificate",
    "KKTError",
    "NotConvergedError",
    "SolveResult",
    "active_set_solve",
    "cvxpy_solve",
    "exact_route",
    "installed_qp_solvers",
    "kkt_certificate",
    "multigrid_solve",
    "route_functions",
    "solve",
]
