"""Solving (S_h): an exact active-set route (``direct``, ``multigrid`` or ``auto``) with a cascade
warm start, or any solver route of ``signorini.solvers``."""

from __future__ import annotations

import logging

import numpy as np

from signorini.fem.discrete import DiscreteProblem, build, interpolate_fk
from signorini.solvers import EXACT_SOLVERS, NotConvergedError, SolveResult, solve

log = logging.getLogger(__name__)

CASCADE_FACTOR = 4  # coarse level N // 4 provides the warm start of level N
CASCADE_MIN_N = 24  # below this, solve cold


def cascade_start(disc: DiscreteProblem, solver: str = "direct", **options) -> np.ndarray | None:
    """The cascade's warm start of level ``N``: the solution on the coarser mesh
    ``N // CASCADE_FACTOR`` (itself solved with the cascade) interpolated onto ``disc``'s
    nodes; None below ``CASCADE_MIN_N`` (the cascade solves cold there).  What
    ``solve_discrete(..., warm_start="cascade")`` starts from, and what the work-precision
    study hands other solvers as the same initial guess."""
    Nc = disc.N // CASCADE_FACTOR
    if Nc < CASCADE_MIN_N:
        return None
    coarse = build(disc.problem, Nc, disc.diagonal)
    uc = solve_discrete(coarse, solver, "cascade", **options).u
    return interpolate_fk(Nc, disc.diagonal, uc, disc.mesh.p)


def solve_discrete(
    disc: DiscreteProblem, solver: str = "direct", warm_start: str | np.ndarray | None = "cascade", **options
) -> SolveResult:
    """Solve (S_h).  For the exact routes (``solvers.routes.EXACT_SOLVERS``),
    ``warm_start="cascade"`` first solves on the coarser mesh ``N // CASCADE_FACTOR``
    (recursively, with the same route name: ``auto`` picks by each mesh's size) and starts from
    its interpolant (``cascade_start``); when the active set does not settle from that start in
    ``max_iter`` steps, the solve is repeated from the cold start."""
    if solver in EXACT_SOLVERS:
        if isinstance(warm_start, str):
            if warm_start != "cascade":
                raise ValueError(f"unknown warm start {warm_start!r}; use 'cascade', None or a vector")
            warm_start = cascade_start(disc, solver, **options)
            if warm_start is not None:
                options.setdefault("warm_start_dilation", 0)
                try:
                    return solve(solver, disc.A, disc.b, disc.boundary, **options, warm_start=warm_start)
                except NotConvergedError as err:
                    log.warning("N=%d: cascade start did not settle (%s); solving from the cold start", disc.N, err)
                    options.pop("warm_start_dilation", None)
                    warm_start = None
        options["warm_start"] = warm_start
    return solve(solver, disc.A, disc.b, disc.boundary, **options)
