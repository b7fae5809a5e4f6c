"""The solver routes by name: what ``signorini.solvers.solve`` dispatches to, whether a route is
exact, and the options each accepts.

Both exact routes are the primal–dual active-set iteration (``solvers.pdas``); they differ in how
a Newton system is solved: ``direct`` by a sparse factorisation (``solvers.active_set``), and
``multigrid`` by conjugate gradients preconditioned with a multigrid V-cycle (``solvers.multigrid``).
``cvxpy`` hands the QP to a cvxpy QP solver (an inexact cross-check).  A configuration names a
route, an alias of one (``active_set``: the direct route's earlier name, which configurations and
the recorded results keep), ``auto`` (``multigrid`` from ``MULTIGRID_FROM_UNKNOWNS`` unknowns on,
``direct`` below) or ``cvxpy_<QP solver>`` (the QP solver in the name).

The workflow's config checks read this module while Snakemake parses the workflow, so it imports
the standard library only; the dispatcher imports the routes' functions (``solvers.solve``), and
``tests/solvers/test_routes.py`` compares each route's options with its function's signature and
the names with the config schema's.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Option:
    """What an option accepts: values of ``kind`` (None: any), and null when ``nullable``; its
    ``default`` where known (the routes' own)."""

    kind: type | None
    nullable: bool = False
    default: object = None


@dataclass(frozen=True)
class Route:
    """A solver route: its function ``function`` of module ``module`` called as
    ``function(A, b, constrained, **options)``, whether it is ``exact`` (certified to round-off,
    started from the cascade), the keyword ``options`` it accepts, in the order of its signature,
    and for a route that hands the QP to a named QP solver the parameter ``qp_parameter`` that
    names it (a route without an initial guess: a warm start is dropped)."""

    name: str
    module: str
    function: str
    exact: bool
    options: Mapping[str, Option] = field(default_factory=dict)
    qp_parameter: str | None = None


# the options the active-set iteration takes on either route (solvers.pdas)
_ACTIVE_SET = {
    "warm_start": Option(None, nullable=True),
    "max_iter": Option(int, default=100),
    "kkt_tol": Option(float, default=1e-10),
}

DIRECT = Route(
    "direct",
    "signorini.solvers.active_set",
    "active_set_solve",
    exact=True,
    options={
        **_ACTIVE_SET,
        "refactor_above": Option(int, default=40),
        "frontier_growth": Option(bool, default=True),
        "warm_start_dilation": Option(int, default=0),
        "backend": Option(str, default="auto"),
        "warm_start_reach": Option(int, default=2),
    },
)
MULTIGRID = Route(
    "multigrid",
    "signorini.solvers.multigrid",
    "multigrid_solve",
    exact=True,
    options={
        **_ACTIVE_SET,
        "frontier_growth": Option(bool, default=True),
        "warm_start_dilation": Option(int, default=0),
        "amg": Option(str, default="geometric"),
        "tol": Option(float, default=1e-14),
        "inner_rtol": Option(float, default=1e-8),
        "max_cg_iter": Option(int, default=500),
        "max_coarse": Option(int, default=500),
        "local_release": Option(bool, default=True),
        "warm_start_reach": Option(int, default=2),
    },
)
CVXPY = Route(
    "cvxpy",
    "signorini.solvers.cvxpy_qp",
    "cvxpy_solve",
    exact=False,
    options={
        "tol": Option(float, nullable=True),
        "kkt_tol": Option(float, default=1e-6),
        "check": Option(bool, default=True),
        "normalize": Option(bool, default=False),
    },
    qp_parameter="solver",
)

ROUTES: dict[str, Route] = {route.name: route for route in (DIRECT, MULTIGRID, CVXPY)}
ALIASES = {"active_set": "direct"}  # the direct route's earlier name: configurations keep it
AUTO = "auto"
QP_OPTION = "qp_solver"  # the option naming the QP solver of the ``cvxpy`` route
DEFAULT_QP_SOLVER = "CLARABEL"
QP_SHORTHANDS = ("clarabel", "osqp", "scs")  # the cvxpy_<QP solver> names the config schema lists
# ``auto`` takes the multigrid route from this many unknowns on (N ≈ 345): the crossover of the
# two routes on the paper's problem with the cascade and the geometric hierarchy, timed side by
# side (docs/evidence/design-measurements.md#multigrid-crossover)
MULTIGRID_FROM_UNKNOWNS = 120_000

SOLVERS = (*ROUTES, AUTO)  # the routes by their names, and the choice between the exact ones
# the names of the certified active-set routes (the cascade starts them)
EXACT_SOLVERS = (
    *(name for name, route in ROUTES.items() if route.exact),
    *(alias for alias, name in ALIASES.items() if ROUTES[name].exact),
    AUTO,
)


def config_names() -> tuple[str, ...]:
    """Every name the config schema lists for a scene's solver: the routes with ``auto``, the
    aliases and the ``cvxpy_<QP solver>`` shorthands."""
    return (*SOLVERS, *ALIASES, *(f"{CVXPY.name}_{qp}" for qp in QP_SHORTHANDS))


def canonical(name: str) -> str:
    """The route an alias names; any other name as it is."""
    return ALIASES.get(name, name)


def exact_route(name: str, n: int) -> str:
    """The route ``name`` takes for ``n`` unknowns: ``auto`` resolved by size, an alias to its
    route, others as named."""
    if name == AUTO:
        return MULTIGRID.name if n >= MULTIGRID_FROM_UNKNOWNS else DIRECT.name
    return canonical(name)


def resolve(name: str, n: int) -> tuple[Route, str | None]:
    """The route a solve by ``name`` with ``n`` unknowns takes, and the QP solver the name gives
    (``cvxpy_osqp``: ``osqp``; None otherwise); ``ValueError`` naming an unknown name."""
    route = exact_route(name, n)
    if route in ROUTES:
        return ROUTES[route], None
    prefix = f"{CVXPY.name}_"
    if route.startswith(prefix) and len(route) > len(prefix):
        return CVXPY, route.removeprefix(prefix)
    raise ValueError(f"unknown solver {name!r}; choose one of {(*SOLVERS, *ALIASES)} or cvxpy_<QP solver>")
