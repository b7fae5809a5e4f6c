"""Solving (S_h): the exact active-set solver with a cascade warm start, or any solver route
of ``signorini.solvers``."""

from __future__ import annotations

import numpy as np

from signorini.fem.discrete import DiscreteProblem, build, interpolate_fk
from signorini.solvers import SolveResult, solve

CASCADE_FACTOR = 4  # coarse level N // 4 provides the warm start of level N
CASCADE_MIN_N = 24  # below this, solve cold


def solve_discrete(
    disc: DiscreteProblem, solver: str = "active_set", warm_start: str | np.ndarray | None = "cascade", **options
) -> SolveResult:
    """Solve (S_h).  For ``active_set``, ``warm_start="cascade"`` first solves on the
    coarser mesh ``N // CASCADE_FACTOR`` (recursively) and starts from its interpolant."""
    if solver == "active_set":
        if isinstance(warm_start, str):
            if warm_start != "cascade":
                raise ValueError(f"unknown warm start {warm_start!r}; use 'cascade', None or a vector")
            warm_start = None
            Nc = disc.N // CASCADE_FACTOR
            if Nc >= CASCADE_MIN_N:
                coarse = build(disc.problem, Nc, disc.diagonal)
                uc = solve_discrete(coarse, solver, "cascade", **options).u
                warm_start = interpolate_fk(Nc, disc.diagonal, uc, disc.mesh.p)
                options.setdefault("warm_start_dilation", 0)
        options["warm_start"] = warm_start
    return solve(solver, disc.A, disc.b, disc.boundary, **options)
