"""How the work-precision study runs a solver route: the kind of a configuration, and the routes
that run in this process.

A configuration's *kind* says how the study treats it: ``EXACT``, one of our certified active-set
routes (``signorini.solvers.EXACT_SOLVERS``), run once per mesh and labelled ``exact``; ``QP``, a
QP solver run in this process at its default and at every swept tolerance (cvxpy's, named
``cvxpy_<solver>``); ``PEER``, a PETSc method run like a QP solver by the external driver
(``peers``).  ``study.ROUTES`` maps each route's name to its ``Runner``, ``study.kind_of`` resolves
a name.  A new in-process route is a module with a ``Runner`` (its libraries imported inside its
methods: the workflow reads the registry while it plans) and an entry of ``study.ROUTES``.
"""

from __future__ import annotations

import contextlib
import enum
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from signorini.solvers import routes as solver_routes

if TYPE_CHECKING:
    from signorini.studies.work_precision.study import SolverConfig

QP_PREFIX = f"{solver_routes.CVXPY.name}_"  # cvxpy_<solver>: one of cvxpy's QP solvers (signorini.solvers.routes)


class Kind(enum.Enum):
    """How the study runs a configuration (module docstring)."""

    EXACT = "exact"
    QP = "qp"
    PEER = "peer"


@dataclass
class Attempt:
    """What one run of a route gave: its result (a ``SolveResult``, or None), status, reason, the CPU
    seconds of its samples, and further record fields (``timing``: the protocol's summary; a peer's
    set-up time, converged reason and provenance)."""

    result: Any
    status: str
    reason: str
    times: list[float]
    extra: dict = field(default_factory=dict)


class Runner:
    """A route run in this process: the options of its call and the residual its answer must reach,
    the call, a warm-up, its log file, and how the table names it."""

    kind = Kind.QP

    def settings(self, config: SolverConfig, tol: float | None, limit: float | None) -> tuple[dict, float]:
        """The options of a call at tolerance ``tol`` (None: the solver's default) with a time limit of
        ``limit`` seconds where the solver takes one, and the worst relative KKT residual its answer
        must reach."""
        raise NotImplementedError

    def call(self, config: SolverConfig, disc: Any, tol: float | None, options: dict) -> Callable[[], tuple]:
        """The call ``timing.Timer`` times on ``disc`` (a ``DiscreteProblem``): ``(SolveResult, None)``."""
        raise NotImplementedError

    def warm_up(self, config: SolverConfig) -> None:
        """Load the route's libraries, so that the first timed call pays no import."""

    def log_option(self, config: SolverConfig) -> str | None:
        """The option that sends the solver's log to a file (its own words on a failure), or None."""
        return None

    def table_name(self, route: str) -> str:
        """The solver as ``work_precision.csv`` names it."""
        return route


class Exact(Runner):
    """Our certified active-set routes through ``fem.solve.solve_discrete`` (``warm_start``: the
    cascade unless null), certified to ``kkt_tol`` (the routes' default: ``solvers.routes``); a
    tolerance does not apply."""

    kind = Kind.EXACT

    def settings(self, config: SolverConfig, tol: float | None, limit: float | None) -> tuple[dict, float]:
        options = dict(config.options)
        return options, float(options.get("kkt_tol", solver_routes.DIRECT.options["kkt_tol"].default))

    def call(self, config: SolverConfig, disc: Any, tol: float | None, options: dict) -> Callable[[], tuple]:
        from signorini.fem.solve import solve_discrete

        options = dict(options)
        warm = options.pop("warm_start", "cascade")
        return lambda: (solve_discrete(disc, config.solver, warm_start=warm, **options), None)


# cvxpy's option that limits the wall time of one solve (seconds), by cvxpy's name of the solver
TIME_LIMIT_OPTIONS = {
    "CLARABEL": "time_limit",
    "OSQP": "time_limit",
    "SCS": "time_limit_secs",
    "HIGHS": "time_limit",
    "PIQP": "max_time",
    "PROXQP": "max_time",  # hypothetical mapping for solvers not installed here
}
LOG_FILE_OPTIONS = {"HIGHS": "log_file"}  # solvers whose log can go to a file (failure reasons)


class Cvxpy(Runner):
    """cvxpy's QP solver of ``cvxpy_<solver>`` through ``solvers.cvxpy_solve`` (canonicalisation
    included), every tolerance option of the solver set to the tolerance
    (``cvxpy_qp.TOLERANCE_OPTIONS``; at its default, the answer must reach the solver's default)."""

    @staticmethod
    def qp_solver(route: str) -> str:
        """cvxpy's name of the route's solver: ``cvxpy_osqp`` → ``OSQP``."""
        return route.removeprefix(QP_PREFIX).upper()

    def settings(self, config: SolverConfig, tol: float | None, limit: float | None) -> tuple[dict, float]:
        from signorini.solvers.cvxpy_qp import TOLERANCE_OPTIONS

        options, qp = dict(config.options), self.qp_solver(config.solver)
        if limit is not None and qp in TIME_LIMIT_OPTIONS:
            options.setdefault(TIME_LIMIT_OPTIONS[qp], float(limit))
        default = TOLERANCE_OPTIONS.get(qp, ((), math.nan))[1]
        return options, float(tol) if tol is not None else float(default)

    def call(self, config: SolverConfig, disc: Any, tol: float | None, options: dict) -> Callable[[], tuple]:
        from signorini.solvers import cvxpy_solve

        qp = self.qp_solver(config.solver)
        return lambda: (cvxpy_solve(disc.A, disc.b, disc.boundary, qp, tol=tol, check=False, **options), None)

    def warm_up(self, config: SolverConfig) -> None:
        """A 3-unknown QP."""
        import numpy as np
        import scipy.sparse as sp

        from signorini.solvers import cvxpy_solve

        with contextlib.suppress(Exception):
            A = sp.identity(3, format="csr") * 2.0
            qp = self.qp_solver(config.solver)
            cvxpy_solve(A, np.array([1.0, -1.0, 1.0]), np.array([0, 1]), qp, check=False, **config.options)

    def log_option(self, config: SolverConfig) -> str | None:
        return LOG_FILE_OPTIONS.get(self.qp_solver(config.solver))

    def table_name(self, route: str) -> str:
        return self.qp_solver(route)


class Peer(Runner):
    """A PETSc peer: run by its driver (``peers.run_peer``, through ``signorini.peers``), not in this process."""

    kind = Kind.PEER


EXACT, CVXPY, PEER = Exact(), Cvxpy(), Peer()
