"""Stage ``norm``: one norm of ``u − u_h`` per job (scene, ``N``, norm), so that a target
computes only the norms it needs."""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Mapping

from signorini.fem.mesh import friedrichs_keller, mesh_width
from signorini.fem.norms import Conventions, evaluate_norms, parse_norm
from signorini.fem.problem import Problem
from signorini.pipeline.artifacts import save_json
from signorini.studies.scene.store import load_solution

log = logging.getLogger(__name__)


def norm_stage(
    problem_params: Mapping,
    N: int,
    diagonal: str,
    solution_npz: str | os.PathLike,
    norm: str,
    out_json: str | os.PathLike,
    conventions: Mapping | None = None,
) -> dict:
    """One norm of ``u - u_h`` on the mesh with ``N`` cells per side; saves value and timing."""
    parse_norm(norm)  # fail before any work on an unknown name
    problem = Problem.from_params(problem_params)
    conv = Conventions(**dict(conventions or {}))
    u_h = load_solution(solution_npz, N, diagonal)
    t0 = time.perf_counter()
    mesh = friedrichs_keller(int(N), diagonal)
    t1 = time.perf_counter()
    value = evaluate_norms(problem, mesh, u_h, [norm], conv)[norm]  # chunked: bounded memory
    t2 = time.perf_counter()
    log.info("N=%d %s = %.6e (mesh %.2f s, norm %.3f s)", N, norm, value, t1 - t0, t2 - t1)
    info = {
        "N": int(N),
        "h": mesh_width(int(N)),
        "norm": norm,
        "value": float(value),
        "conventions": conv.as_dict(),
        "diagonal": diagonal,
        "timings": {
            "mesh_s": t1 - t0,
            "norm_s": t2 - t1,
            "note": "perf_counter timers inside the job: mesh = building the mesh, norm = error evaluation + reduction",
        },
    }
    save_json(out_json, info)
    return info
