"""Stage ``norm``: norms of ``u − u_h`` on one mesh of a scene.  By default one job per norm, so
that a target computes only the norms it needs; with ``norm_jobs: per_mesh`` one job computes all
of a scene's norms on a mesh (fewer, longer jobs for a cluster), through the same function: there
the norms under the conventions share one evaluation of the error field per chunk and rule."""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.evaluate import evaluate_named_norms
from signorini.fem.norms.names import NormName, norm_name, parse_norm_name
from signorini.pipeline.artifacts import save_json
from signorini.studies.scene.store import SceneMesh

if TYPE_CHECKING:
    import numpy as np
    from skfem import MeshTri

log = logging.getLogger(__name__)
TIMINGS_NOTE = (
    "perf_counter timers inside the job: mesh = building the mesh, norm = error evaluation + reduction "
    "(for the norms of norm_shared_by together: one evaluation of the error field shared by them)"
)


def _evaluate(at: SceneMesh, mesh, u_h, norms: list[NormName], conv: Conventions) -> dict[str, tuple]:
    """{name: (value, accuracy or None, seconds, names sharing the evaluation)}: the norms under
    the conventions in one call of the dispatcher (one error field), each ``_true`` norm alone."""
    plain = [spec for spec in norms if not spec.true]
    groups = ([plain] if plain else []) + [[spec] for spec in norms if spec.true]
    out = {}
    for group in groups:
        names = [spec.name for spec in group]
        t1 = time.perf_counter()
        results = evaluate_named_norms(at.problem, mesh, u_h, group, conv, details=True)
        seconds = time.perf_counter() - t1
        for name, result in results.items():
            if isinstance(result, float):
                out[name] = (result, None, seconds, names)
            else:
                accuracy = {k: v for k, v in result.as_dict().items() if k not in ("name", "value")}
                out[name] = (result.value, accuracy, seconds, names)
    return out

# The uncertainty of a value is this multiple of the same norm of the algebraic error δ: δ is the
# first-order estimate from this run's KKT residual, and on another processor u_h moves by a
# different round-off of the same size, far below the estimate
# (docs/evidence/design-measurements.md#uncertainty-safety)
UNCERTAINTY_SAFETY = 10.0
UNCERTAINTY_NOTE = (
    "|value - the same norm of u - u_h*| <= the norm of delta = u_h - u_h* (triangle inequality); "
    "estimate = that norm of the first-order delta of the solve artifact, uncertainty = safety x estimate"
)


def uncertainty_norm(norm: str | NormName) -> str:
    """The norm whose value on ``δ = u_h − u_h*`` bounds the change of ``norm`` of ``u − u_h``: the
    norm itself under the paper's conventions (a ``_true`` norm's rule-based twin); for a one-sided
    ``Lpplus``/``Lpminus`` the two-sided ``Lp`` (``‖(e + δ)⁺‖ ≤ ‖e⁺‖ + ‖δ‖``)."""
    spec = norm_name(norm)
    return spec.base.removesuffix(spec.part) if spec.part else spec.base


def algebraic_uncertainties(
    at: SceneMesh, mesh: MeshTri, delta: np.ndarray, norms: Sequence[str | NormName], conv: Conventions
) -> dict[str, dict]:
    """{norm: the norm of the algebraic error ``δ`` (a P1 function: the error of ``-δ`` against
    ``u ≡ 0``) that bounds how far round-off can move the value of ``norm``, and the uncertainty
    recorded}; the norms of ``δ`` are evaluated together (one error field)."""
    zero = at.problem.vanishing()  # u ≡ 0 on the same boundary pieces
    names = {norm_name(norm).name: uncertainty_norm(norm) for norm in norms}
    values = evaluate_named_norms(zero, mesh, -delta, list(dict.fromkeys(names.values())), conv)
    return {
        norm: {
            "estimate": float(values[name]),
            "norm": name,
            "safety": UNCERTAINTY_SAFETY,
            "uncertainty": UNCERTAINTY_SAFETY * float(values[name]),
            "note": UNCERTAINTY_NOTE,
        }
        for norm, name in names.items()
    }


def norms_stage(
    at: SceneMesh,
    solution_npz: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    conventions: Mapping,
) -> dict[str, dict]:
    """Norms of ``u - u_h`` on one mesh of a scene, each saved to its own JSON (``outputs``:
    norm name -> path) with its value and timing, on one mesh built once: the norms under the
    conventions together (``fem.norms.evaluate.evaluate_named_norms``: each value the one a job of that
    norm alone computes, bit for bit), then each ``_true`` norm, which also saves its estimated
    quadrature error and refinement levels.  With the solve artifact's ``algebraic_error`` each
    artifact also records how far round-off in ``u_h`` can move its value (``algebraic_error``:
    ``algebraic_uncertainties``), from which the tables take their digits."""
    specs = [parse_norm_name(norm) for norm in outputs]  # fail before any work on an unknown name
    conv = Conventions(**dict(conventions))
    solution = at.solution(solution_npz)
    u_h, delta = solution["u"], solution.get("algebraic_error")
    t0 = time.perf_counter()
    mesh = at.triangles()  # the norms read p and t alone: no scikit-fem in this job
    mesh_s = time.perf_counter() - t0
    shared = {"mesh_shared_by": list(outputs)} if len(outputs) > 1 else {}
    infos = {}
    values = _evaluate(at, mesh, u_h, specs, conv)
    uncertainties = {} if delta is None else algebraic_uncertainties(at, mesh, delta, specs, conv)
    for norm, (value, accuracy, norm_s, group) in values.items():
        if not math.isfinite(value) or value < 0.0:
            raise ValueError(
                f"N={at.N} {norm} = {value}: not a finite non-negative number (overflow or NaN in u - u_h)"
            )
        algebraic = uncertainties.get(norm)
        log.info("N=%d %s = %.6e (mesh %.2f s, norm %.3f s)", at.N, norm, value, mesh_s, norm_s)
        timings = {"mesh_s": mesh_s, "norm_s": norm_s, **shared}
        if len(group) > 1:
            timings["norm_shared_by"] = group
        infos[norm] = {
            "N": at.N,
            "h": at.h,
            "norm": norm,
            "value": float(value),
            "conventions": conv.as_dict(),
            **({"quadrature_error": accuracy} if accuracy else {}),
            **({"algebraic_error": algebraic} if algebraic else {}),
            "diagonal": at.diagonal,
            **({} if at.paper_mesh else {"mesh": dict(at.mesh_spec)}),
            "timings": {**timings, "note": TIMINGS_NOTE},
        }
        save_json(outputs[norm], infos[norm])
    return infos


def norm_stage(
    at: SceneMesh, solution_npz: str | os.PathLike, norm: str, out_json: str | os.PathLike, conventions: Mapping
) -> dict:
    """One norm of ``u - u_h`` on one mesh of a scene (``norms_stage`` with one norm)."""
    return norms_stage(at, solution_npz, {norm: out_json}, conventions)[norm]
