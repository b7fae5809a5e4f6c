"""Stage ``norm``: norms of ``u − u_h`` on one mesh of a scene.  By default one job per norm, so
that a target computes only the norms it needs; with ``norm_jobs: per_mesh`` one job computes all
of a scene's norms on a mesh (fewer, longer jobs for a cluster), through the same function."""

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
TIMINGS_NOTE = "perf_counter timers inside the job: mesh = building the mesh, norm = error evaluation + reduction"


def norms_stage(
    at: SceneMesh,
    solution_npz: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    conventions: Mapping,
) -> dict[str, dict]:
    """Norms of ``u - u_h`` on one mesh of a scene, each saved to its own JSON (``outputs``:
    norm name -> path) with its value and timing, one after another on one mesh built once (each
    value is the one a job of that norm alone computes).  A ``_true`` norm (``fem.true_norms``)
    also saves its estimated quadrature error and refinement levels."""
    specs = {norm: parse_norm_name(norm) for norm in outputs}  # fail before any work on an unknown name
    conv = Conventions(**dict(conventions))
    u_h = at.load_solution(solution_npz)
    t0 = time.perf_counter()
    mesh = at.mesh()
    mesh_s = time.perf_counter() - t0
    shared = {"mesh_shared_by": list(outputs)} if len(outputs) > 1 else {}
    infos = {}
    for norm, out_json in outputs.items():
        t1 = time.perf_counter()
        accuracy = None
        if specs[norm].true:
            from signorini.fem.true_norms import true_norm

            result = true_norm(at.problem, mesh, u_h, norm, conv)
            value = result.value
            accuracy = {k: v for k, v in result.as_dict().items() if k not in ("name", "value")}
        else:
            value = evaluate_norms(at.problem, mesh, u_h, [norm], conv)[norm]  # chunked: bounded memory
        norm_s = time.perf_counter() - t1
        if not math.isfinite(value) or value < 0.0:
            raise ValueError(
                f"N={at.N} {norm} = {value}: not a finite non-negative number (overflow or NaN in u - u_h)"
            )
        log.info("N=%d %s = %.6e (mesh %.2f s, norm %.3f s)", at.N, norm, value, mesh_s, norm_s)
        infos[norm] = {
            "N": at.N,
            "h": at.h,
            "norm": norm,
            "value": float(value),
            "conventions": conv.as_dict(),
            **({"quadrature_error": accuracy} if accuracy else {}),
            "diagonal": at.diagonal,
            "timings": {"mesh_s": mesh_s, "norm_s": norm_s, **shared, "note": TIMINGS_NOTE},
        }
        save_json(out_json, infos[norm])
    return infos


def norm_stage(
    at: SceneMesh, solution_npz: str | os.PathLike, norm: str, out_json: str | os.PathLike, conventions: Mapping
) -> dict:
    """One norm of ``u - u_h`` on one mesh of a scene (``norms_stage`` with one norm)."""
    return norms_stage(at, solution_npz, {norm: out_json}, conventions)[norm]
