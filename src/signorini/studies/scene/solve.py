"""Stage ``solve``: solve (S_h) on the assembled system of one scene and ``N``, certified.

Writes ``solution.npz`` (``u``, ``λ``, the contact set and ``algebraic_error``, the first-order
algebraic error ``δ ≈ u_h − u_h*`` of ``solvers.algebraic_error.linearised_error``) and
``solution.json`` (the KKT certificate, the size of ``δ``, iterations and timers).  The norm
stage evaluates each norm of ``δ`` next to the error's: the digits of a reported value that
round-off cannot change (``signorini.formatting.certified_digits``).  A solution without a valid KKT certificate raises
``KKTError`` (the residuals are in its message, hence in the job's log) and nothing is written.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Mapping

from signorini.fem.discrete import DiscreteProblem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.artifacts import save_json, save_npz
from signorini.solvers import exact_route
from signorini.solvers.algebraic_error import linearised_error
from signorini.solvers.multigrid import compact
from signorini.solvers.routes import MULTIGRID
from signorini.studies.scene.store import SceneMesh, load_system

log = logging.getLogger(__name__)


def solve_stage(
    at: SceneMesh,
    system_npz: str | os.PathLike,
    solver: str,
    out_npz: str | os.PathLike,
    out_json: str | os.PathLike,
    solver_options: Mapping | None = None,
) -> dict:
    """Solve (S_h) from the ``discretise`` archive; save ``u``, ``λ``, the contact set and the diagnostics."""
    problem, N, diagonal = at.problem, at.N, at.diagonal
    t0 = time.perf_counter()
    A, b, boundary = load_system(system_npz, N)
    route = exact_route(solver, b.size)  # the direct route's factorisation for any route but multigrid
    if route == MULTIGRID.name:  # a large grid's matrix as its stencil: its values not held while solving
        A = compact(A)
    mesh = None if at.paper_mesh else at.mesh()  # the cascade interpolates onto its vertices
    disc = DiscreteProblem(problem, N, diagonal, mesh, A, b, boundary)
    t1 = time.perf_counter()
    result = solve_discrete(disc, solver=solver, **dict(solver_options or {}))
    t2 = time.perf_counter()
    algebraic = linearised_error(A, b, boundary, result.u, result.lam, result.active, route, result.hierarchy)
    result.hierarchy = None  # its memory, before the archive is written
    log.info(
        "N=%d solver=%s iterations=%d active=%d certificate: %s; algebraic error max |δ| = %.1e, energy %.1e",
        N,
        solver,
        result.iterations,
        result.active.size,
        result.certificate.describe(),
        float(abs(algebraic.delta).max(initial=0.0)),
        algebraic.energy,
    )
    info = {
        "N": N,
        "h": at.h,
        "diagonal": diagonal,
        **({} if at.paper_mesh else {"mesh": dict(at.mesh_spec)}),
        "problem": problem.as_dict(),
        "solver_requested": solver,
        "solver_options": dict(solver_options or {}),
        "n_dofs": int(result.u.size),
        "n_constrained": int(boundary.size),
        "timings": {
            "load_s": t1 - t0,
            "solve_s": t2 - t1,
            "note": "perf_counter timers inside the job: load = reading the assembled system and the mesh; "
            "solve = solve_discrete incl. the warm-start cascade; summary.wall_time_s = final solver call only",
        },
        "summary": result.summary(),
        "algebraic_error": algebraic.summary(result.u),
    }
    save_npz(
        out_npz,
        u=result.u,
        lam=result.lam,
        active=result.active,
        algebraic_error=algebraic.delta,
        N=N,
        diagonal=diagonal,
    )
    save_json(out_json, info)
    return info
