"""Solvers for the discrete Signorini QP behind one interface.

``solve(name, A, b, constrained, **options)`` with ``name`` one of ``SOLVERS``:
``active_set`` (exact, certified, a sparse factorisation: the direct route), ``multigrid``
(exact, certified, the same active-set iteration with multigrid-preconditioned CG: O(n)),
``auto`` (``multigrid`` from ``MULTIGRID_FROM_UNKNOWNS`` unknowns on, ``active_set`` below) or
``cvxpy`` (any installed cvxpy QP solver chosen by the ``qp_solver`` option); a shorthand
``cvxpy_clarabel``, ``cvxpy_osqp``, … selects the QP solver in the name.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import scipy.sparse as sp

    from signorini.solvers.result import SolveResult

SOLVERS = ("active_set", "multigrid", "auto", "cvxpy")
EXACT_SOLVERS = ("active_set", "multigrid", "auto")  # the certified active-set routes
# ``auto`` takes the multigrid route from this many unknowns on (N ≈ 345): the crossover of the
# two routes on the paper's problem with the cascade and the geometric hierarchy, measured side by
# side in one process on one thread at N = 201 to 451 (CPU seconds, two runs each: even at 201
# and 301 within the runs' spread, multigrid ahead at 351, ×1.6 at 401 and ×1.9 at 451)
MULTIGRID_FROM_UNKNOWNS = 120_000


def exact_route(name: str, n: int) -> str:
    """The route ``name`` takes for ``n`` unknowns: ``auto`` resolved by size, others as named."""
    if name == "auto":
        return "multigrid" if n >= MULTIGRID_FROM_UNKNOWNS else "active_set"
    return name


def solve(name: str, A: sp.spmatrix, b: np.ndarray, constrained: np.ndarray, **options) -> SolveResult:
    """Dispatch to a solver route by name; unknown names raise ``ValueError``."""
    from signorini.solvers.active_set import active_set_solve
    from signorini.solvers.cvxpy_qp import cvxpy_solve
    from signorini.solvers.multigrid import multigrid_solve

    name = exact_route(name, len(b))
    if name == "active_set":
        return active_set_solve(A, b, constrained, **options)
    if name == "multigrid":
        return multigrid_solve(A, b, constrained, **options)
    if name == "cvxpy":
        options.pop("warm_start", None)
        return cvxpy_solve(A, b, constrained, solver=options.pop("qp_solver", "CLARABEL"), **options)
    if name.startswith("cvxpy_"):
        options.pop("warm_start", None)
        return cvxpy_solve(A, b, constrained, solver=name.removeprefix("cvxpy_"), **options)
    raise ValueError(f"unknown solver {name!r}; choose one of {SOLVERS} or cvxpy_<QP solver>")


def __getattr__(name: str) -> Any:
    """The routes and the certificate's names, imported when first asked for: the names above
    (the routes' names, ``exact_route``) serve the workflow's config checks, which must not pay for
    numpy, scipy and cvxpy while Snakemake parses the workflow."""
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
    "solve",
]
