"""Stage ``norm``: norms of ``u − u_h`` on one mesh of a scene.  By default one job per norm, so
that a target computes only the norms it needs; with ``norm_jobs: per_mesh`` one job computes all
of a scene's norms on a mesh (fewer, longer jobs for a cluster), through the same function."""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

from signorini.fem.norm_names import parse_norm_name
from signorini.fem.norms import Conventions, evaluate_norms
from signorini.pipeline.artifacts import save_json
from signorini.studies.scene.store import SceneMesh

if TYPE_CHECKING:
    import numpy as np
    from skfem import MeshTri

log = logging.getLogger(__name__)
TIMINGS_NOTE = "perf_counter timers inside the job: mesh = building the mesh, norm = error evaluation + reduction"
# The uncertainty of a value is this multiple of the same norm of the algebraic error δ: δ is the
# first-order estimate from this run's KKT residual, and on another processor u_h moves by a
# different round-off of the same size (measured: 200x below the estimate at N = 501)
UNCERTAINTY_SAFETY = 10.0
UNCERTAINTY_NOTE = (
    "|value - the same norm of u - u_h*| <= the norm of delta = u_h - u_h* (triangle inequality); "
    "estimate = that norm of the first-order delta of the solve artifact, uncertainty = safety x estimate"
)


def uncertainty_norm(norm: str) -> str:
    """The norm whose value on ``δ = u_h − u_h*`` bounds the change of ``norm`` of ``u − u_h``: the
    norm itself under the paper's conventions (a ``_true`` norm's rule-based twin); for a one-sided
    ``Lpplus``/``Lpminus`` the two-sided ``Lp`` (``‖(e + δ)⁺‖ ≤ ‖e⁺‖ + ‖δ‖``)."""
    spec = parse_norm_name(norm)
    return spec.base.removesuffix(spec.part) if spec.part else spec.base


def algebraic_uncertainty(at: SceneMesh, mesh: MeshTri, delta: np.ndarray, norm: str, conv: Conventions) -> dict:
    """The norm of the algebraic error ``δ`` (a P1 function: the error of ``-δ`` against ``u ≡ 0``)
    that bounds how far round-off can move the value of ``norm``, and the uncertainty recorded."""
    zero = replace(at.problem, A=0.0)  # u ≡ 0, same free point: the same boundary pieces
    name = uncertainty_norm(norm)
    estimate = float(evaluate_norms(zero, mesh, -delta, [name], conv)[name])
    return {
        "estimate": estimate,
        "norm": name,
        "safety": UNCERTAINTY_SAFETY,
        "uncertainty": UNCERTAINTY_SAFETY * estimate,
        "note": UNCERTAINTY_NOTE,
    }


def norms_stage(
    at: SceneMesh,
    solution_npz: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    conventions: Mapping,
) -> dict[str, dict]:
    """Norms of ``u - u_h`` on one mesh of a scene, each saved to its own JSON (``outputs``:
    norm name -> path) with its value and timing, one after another on one mesh built once (each
    value is the one a job of that norm alone computes).  A ``_true`` norm (``fem.true_norms``)
    also saves its estimated quadrature error and refinement levels.  With the solve artifact's
    ``algebraic_error`` each artifact also records how far round-off in ``u_h`` can move its value
    (``algebraic_error``: ``algebraic_uncertainty``), from which the tables take their digits."""
    specs = {norm: parse_norm_name(norm) for norm in outputs}  # fail before any work on an unknown name
    conv = Conventions(**dict(conventions))
    solution = at.solution(solution_npz)
    u_h, delta = solution["u"], solution.get("algebraic_error")
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
        algebraic = None if delta is None else algebraic_uncertainty(at, mesh, delta, norm, conv)
        log.info("N=%d %s = %.6e (mesh %.2f s, norm %.3f s)", at.N, norm, value, mesh_s, norm_s)
        infos[norm] = {
            "N": at.N,
            "h": at.h,
            "norm": norm,
            "value": float(value),
            "conventions": conv.as_dict(),
            **({"quadrature_error": accuracy} if accuracy else {}),
            **({"algebraic_error": algebraic} if algebraic else {}),
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
