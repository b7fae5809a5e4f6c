"""Solving (S_h): an exact active-set route (``direct``, ``multigrid`` or ``auto``) with a cascade
warm start, or any solver route of ``signorini.solvers``."""

from __future__ import annotations

import logging
import time

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
    return _cascade(disc, solver, options)[0]


def _cascade(disc: DiscreteProblem, solver: str, options: dict) -> tuple[np.ndarray | None, dict | None]:
    """``cascade_start``'s warm start and what its levels cost: the coarse mesh's ``N``, the seconds
    of building, solving (its own cascade included) and interpolating, the coarse solve's V-cycles
    and work units where its route counts them (in the coarse mesh's units and in the fine
    mesh's: scaled by the ratio of the operators' stored entries), and the coarser levels'
    (``cascade``)."""
    Nc = disc.N // CASCADE_FACTOR
    if Nc < CASCADE_MIN_N:
        return None, None
    t0 = time.perf_counter()
    coarse = build(disc.problem, Nc, disc.diagonal)
    result = solve_discrete(coarse, solver, "cascade", **options)
    start = interpolate_fk(Nc, disc.diagonal, result.u, disc.vertices)
    cost = {"N": Nc, "seconds": time.perf_counter() - t0, "solve_s": result.wall_time_s}
    if "work_units" in result.info:
        ratio = coarse.A.nnz / disc.A.nnz
        below = result.info.get("cascade") or {}
        cost |= {
            "v_cycles": result.info["v_cycles"],
            "work_units": result.info["work_units"],
            "work_units_fine": result.info["work_units"] * ratio + below.get("work_units_fine", 0.0) * ratio,
        }
    if result.info.get("cascade"):
        cost["cascade"] = result.info["cascade"]
    return start, cost


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
            warm_start, cascade = _cascade(disc, solver, options)
            if warm_start is not None:
                options.setdefault("warm_start_dilation", 0)
                try:
                    result = solve(solver, disc.A, disc.b, disc.boundary, **options, warm_start=warm_start)
                    result.info["cascade"] = cascade
                    if "work_units" in result.info and "work_units_fine" in (cascade or {}):
                        # the whole solve's work in this mesh's units
                        result.info["work_units_total"] = result.info["work_units"] + cascade["work_units_fine"]
                    return result
                except NotConvergedError as err:
                    log.warning("N=%d: cascade start did not settle (%s); solving from the cold start", disc.N, err)
                    options.pop("warm_start_dilation", None)
                    warm_start = None
        options["warm_start"] = warm_start
    return solve(solver, disc.A, disc.b, disc.boundary, **options)
