"""Stage ``norm``: one norm of ``u − u_h`` per job (scene, ``N``, norm), so that a target
computes only the norms it needs."""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Mapping

from signorini.fem.norm_names import parse_norm_name
from signorini.fem.norms import Conventions, evaluate_norms
from signorini.pipeline.artifacts import save_json
from signorini.studies.scene.store import SceneMesh

log = logging.getLogger(__name__)


def norm_stage(
    at: SceneMesh, solution_npz: str | os.PathLike, norm: str, out_json: str | os.PathLike, conventions: Mapping
) -> dict:
    """One norm of ``u - u_h`` on one mesh of a scene; saves value and timing.  A ``_true`` norm
    (``fem.true_norms``) also saves its estimated quadrature error and refinement levels."""
    spec = parse_norm_name(norm)  # fail before any work on an unknown name
    N, conv = at.N, Conventions(**dict(conventions))
    u_h = at.load_solution(solution_npz)
    t0 = time.perf_counter()
    mesh = at.mesh()
    t1 = time.perf_counter()
    accuracy = None
    if spec.true:
        from signorini.fem.true_norms import true_norm

        result = true_norm(at.problem, mesh, u_h, norm, conv)
        value = result.value
        accuracy = {k: v for k, v in result.as_dict().items() if k not in ("name", "value")}
    else:
        value = evaluate_norms(at.problem, mesh, u_h, [norm], conv)[norm]  # chunked: bounded memory
    t2 = time.perf_counter()
    if not math.isfinite(value) or value < 0.0:
        raise ValueError(f"N={N} {norm} = {value}: not a finite non-negative number (overflow or NaN in u - u_h)")
    log.info("N=%d %s = %.6e (mesh %.2f s, norm %.3f s)", N, norm, value, t1 - t0, t2 - t1)
    info = {
        "N": N,
        "h": at.h,
        "norm": norm,
        "value": float(value),
        "conventions": conv.as_dict(),
        **({"quadrature_error": accuracy} if accuracy else {}),
        "diagonal": at.diagonal,
        "timings": {
            "mesh_s": t1 - t0,
            "norm_s": t2 - t1,
            "note": "perf_counter timers inside the job: mesh = building the mesh, norm = error evaluation + reduction",
        },
    }
    save_json(out_json, info)
    return info
