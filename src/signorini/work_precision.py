"""Work-precision study: error against run time of every solver on the paper's problem.

What is measured, per mesh ``N`` and per *solver configuration* (``study_configs``):

- ``time_s``: wall time (``time.perf_counter``) of one call of the solver on the assembled
  system, best of 3 when the first call takes under ``REPEAT_BELOW_S`` = 1 s.  For the
  active-set solver the call is ``solve_discrete`` (a cascade warm start includes building
  and solving the coarse levels); for cvxpy it is ``cvxpy_solve`` (cvxpy's canonicalisation
  included; the QP solver's own time is ``solver_time_s``).  Assembly of the level-``N``
  system is common to all configurations and timed once (``build_s``, the ``system`` stage).
- ``iterations`` (Newton steps of the active-set method, iterations of the QP solver) and
  the relative KKT residuals of ``signorini.solvers.certificate`` (computed with the check
  disabled, so an inaccurate answer is recorded, not raised).
- ``status``: ``ok`` (optimal, worst KKT residual ≤ the requested tolerance), ``inaccurate``
  (residual above it, or the solver's own status ``optimal_inaccurate``), ``failed`` (with
  the reason: solver error, time limit, iteration limit, …) or ``skipped`` (predicted to
  fail or to exceed the time limit from the same configuration on the previous mesh).
  A failure never raises: the exception is recorded.
- ``alg_<norm>``: the *algebraic error* ``‖u_h^solver − u_h^exact‖`` against the certified
  exact discrete solution of the source scene, in exact norms of a P1 function (``p1_norms``).
- ``total_<norm>``: the *total error* ``‖u − u_h^solver‖`` with the pipeline's conventions
  (``signorini.norms.evaluate_norms``), and ``disc_<norm>``: the discretisation error
  ``‖u − u_h^exact‖`` read from the source scene's norm artifacts.

The study reuses the source scene's exact solutions (``results/<source>/N<N>/solution.npz``)
and norm artifacts; the assembled system is cached once per mesh (``system_stage``).
``collect_stage`` gathers every record into ``work_precision.csv``;
``signorini.work_precision_report`` turns it into the numbers of ``work_precision.md``.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import logging
import math
import os
import re
import tempfile
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from signorini.artifacts import CorruptArtifactError, atomic_write_text, load_json, load_npz, save_json, save_npz

if TYPE_CHECKING:  # heavy imports stay inside the functions (see pipeline.STAGE_MODULES)
    import pandas as pd
    import scipy.sparse as sp
    from skfem import MeshTri

    from signorini.norms import Conventions

log = logging.getLogger(__name__)

STUDY_NORMS = ("L4", "L16", "Linf", "W14", "W116", "W1inf", "H12")
FIGURE_NORMS = ("L4", "W14")  # the panel rows of work_precision.{pdf,png}
REPEAT_BELOW_S = 1.0  # a solve faster than this is repeated, best of 3
REPEATS = 3
GROWTH_EXPONENT = 1.5  # predicted time ∝ (number of unknowns)^GROWTH_EXPONENT
EXACT_LABEL = "exact"
# cvxpy solver option that limits the wall time of one solve (seconds)
TIME_LIMIT_OPTIONS = {
    "CLARABEL": "time_limit",
    "OSQP": "time_limit",
    "SCS": "time_limit_secs",
    "HIGHS": "time_limit",
    "PIQP": "max_time",
    "PROXQP": "max_time",  # hypothetical mapping for solvers not installed here
}
LOG_FILE_OPTIONS = {"HIGHS": "log_file"}  # solvers whose log can go to a file (failure reasons)


# --- configuration --------------------------------------------------------------------------


class StudyConfigError(ValueError):
    """The ``study`` block of a scene is inconsistent with its source scene."""


@dataclass(frozen=True)
class SolverConfig:
    """One solver configuration: ``solver`` is ``active_set`` or a cvxpy QP solver (upper case);
    ``options`` go to ``solve_discrete`` (active set: ``warm_start``, ``backend``, …) or
    ``cvxpy_solve`` (solver options such as ``polishing``)."""

    name: str
    solver: str
    label: str
    options: dict = field(default_factory=dict)

    @property
    def exact(self) -> bool:
        return self.solver == "active_set"

    def as_dict(self) -> dict:
        return {"name": self.name, "solver": self.solver, "label": self.label, "options": dict(self.options)}


def study_configs(study: Mapping, installed: Sequence[str] | None = None) -> dict[str, SolverConfig]:
    """The configurations of a ``study`` block: its ``configs`` (name → ``{solver, label, options}``)
    plus, with ``qp_solvers: installed`` (or a list of names), one configuration per cvxpy QP
    solver, named by the lower-case solver name, unless a configuration of that name exists."""
    out: dict[str, SolverConfig] = {}
    for name, spec in (study.get("configs") or {}).items():
        solver = str(spec["solver"])
        solver = solver if solver == "active_set" else solver.upper()
        out[name] = SolverConfig(name, solver, str(spec.get("label", name)), dict(spec.get("options") or {}))
    qp = study.get("qp_solvers", [])
    if qp == "installed":
        if installed is None:
            from signorini.solvers import installed_qp_solvers

            installed = installed_qp_solvers()
        qp = list(installed)
    for solver in qp:
        name = solver.lower()
        if name not in out:
            out[name] = SolverConfig(name, solver.upper(), solver.upper(), {})
    for name in out:
        if not re.fullmatch(r"[a-z0-9_]+", name):
            raise StudyConfigError(f"configuration name {name!r}: use lower-case letters, digits and _")
    return out


def check_study(scenes: Mapping, name: str) -> None:
    """The scene ``name`` may reuse its source scene's artifacts: same problem and diagonal,
    its ``N`` a subset of the source's, its norms among the source's and containing L4, W14."""
    scene = scenes[name]
    study = scene.get("study")
    where = f"scenes.{name}.study"
    if not study:
        raise StudyConfigError(f"{where}: missing")
    source = study.get("source")
    if source not in scenes:
        raise StudyConfigError(f"{where}.source: {source!r} is not one of the scenes {sorted(scenes)}")
    src = scenes[source]
    if dict(src["problem"]) != dict(scene["problem"]):
        raise StudyConfigError(f"{where}.source: problem {scene['problem']} differs from {source}'s {src['problem']}")
    if src.get("diagonal", "sw_ne") != scene.get("diagonal", "sw_ne"):
        raise StudyConfigError(f"{where}.source: diagonal differs from {source}'s")
    if src.get("conventions", {}) != scene.get("conventions", {}):
        raise StudyConfigError(f"{where}.source: conventions differ from {source}'s")
    missing = [N for N in scene["N"] if N not in src["N"]]
    if missing:
        raise StudyConfigError(f"scenes.{name}.N: {missing} not among {source}'s N {src['N']}")
    if list(scene["N"]) != sorted(scene["N"]):
        raise StudyConfigError(f"scenes.{name}.N: must be increasing (the time prediction uses the previous N)")
    norms = [n for n in scene["norms"] if n not in src["norms"]]
    if norms:
        raise StudyConfigError(f"scenes.{name}.norms: {norms} not computed by {source}")
    for n in FIGURE_NORMS:
        if n not in scene["norms"]:
            raise StudyConfigError(f"scenes.{name}.norms: the figure needs {n}")
    for N in study.get("figure_N", []):
        if N not in scene["N"]:
            raise StudyConfigError(f"{where}.figure_N: {N} is not one of the scene's N")
    study_configs(study, installed=[])  # names


# --- the cached system ----------------------------------------------------------------------


def system_stage(
    problem_params: Mapping, N: int, diagonal: str, out_npz: str | os.PathLike, out_json: str | os.PathLike
) -> dict:
    """Mesh and assemble (S_h) once per mesh; save ``A`` (CSR arrays), ``b``, the constrained
    nodes and the build time (mesh + assembly + boundary nodes, ``build_s``)."""
    from signorini.discrete import build
    from signorini.problem import Problem

    problem = Problem(**{k: float(v) for k, v in problem_params.items()})
    t0 = time.perf_counter()
    disc = build(problem, int(N), diagonal)
    build_s = time.perf_counter() - t0
    A = disc.A.tocsr()
    save_npz(
        out_npz,
        data=A.data,
        indices=A.indices,
        indptr=A.indptr,
        shape=np.array(A.shape),
        b=disc.b,
        boundary=disc.boundary,
        N=int(N),
        diagonal=diagonal,
    )
    info = {
        "N": int(N),
        "diagonal": diagonal,
        "problem": problem.as_dict(),
        "n_dofs": int(disc.b.size),
        "build_s": build_s,
        "load1": os.getloadavg()[0],
        "note": "build_s: perf_counter around signorini.discrete.build (mesh, assembly, boundary nodes)",
    }
    save_json(out_json, info)
    log.info("N=%d: system built in %.2f s", N, build_s)
    return info


def load_system(path: str | os.PathLike) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """``(A, b, constrained)`` from a ``system_stage`` archive."""
    import scipy.sparse as sp

    d = load_npz(path)
    A = sp.csr_matrix((d["data"], d["indices"], d["indptr"]), shape=tuple(int(s) for s in d["shape"]))
    return A, d["b"], d["boundary"]


# --- norms of a P1 function -----------------------------------------------------------------


def _complete_homogeneous(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, p: int) -> np.ndarray:
    """h_p(v0, v1, v2) = Σ_{a+b+c=p} v0^a v1^b v2^c (elementwise), in O(p) array operations:
    h_m(v0, v1) = v0 h_{m-1}(v0, v1) + v1^m, then h_p = Σ_c v2^c h_{p-c}(v0, v1) by Horner."""
    two = [np.ones_like(v0)]  # h_m(v0, v1), m = 0..p
    power1 = np.ones_like(v1)
    for _ in range(p):
        power1 = power1 * v1
        two.append(v0 * two[-1] + power1)
    out = two[0].copy()
    for m in range(1, p + 1):
        out = out * v2 + two[m]
    return out


def _triangle_power_integrals(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, area: np.ndarray, p: float) -> float:
    """Σ_T ∫_T |v|^p for the linear function with vertex values (v0, v1, v2) on each T.

    Even integer ``p``: exact, ∫_T v^p = 2|T| h_p(v0, v1, v2) / ((p + 1)(p + 2)) (expand
    (Σ vᵢλᵢ)^p and integrate the barycentric monomials).  Otherwise the 64-point conical
    Gauss rule (degree 15).
    """
    if float(p).is_integer() and int(p) % 2 == 0:
        k = int(p)
        return float(np.sum(2.0 * area * _complete_homogeneous(v0, v1, v2, k)) / ((k + 1) * (k + 2)))
    from signorini.quadrature import stroud_conical

    s, t, w = stroud_conical(8)
    lam = np.vstack([1.0 - s, s * (1.0 - t), s * t])  # barycentrics of the conical points (sum 1)
    values = np.outer(v0, lam[0]) + np.outer(v1, lam[1]) + np.outer(v2, lam[2])
    return float(np.sum(area[:, None] * np.abs(values) ** p * w[None, :]))


def p1_norms(
    mesh: MeshTri, v: np.ndarray, names: Sequence[str], conventions: Conventions | None = None
) -> dict[str, float]:
    """The named norms of the P1 function with nodal values ``v`` (an algebraic error).

    Exact for a piecewise linear function: ``Lp`` (even integer ``p``; other ``p`` by a
    degree-15 rule), ``Linf`` (max over the vertices), ``W1p``/``W1inf`` in the form
    ``conventions.w1p_form`` (∇v is constant per triangle), ``H1``, ``L2boundary`` and
    ``H12`` (``conventions.h12_form``, with ∫_e v² = |e| (a² + ab + b²)/3 and ∂_t v constant
    per boundary edge).  The point-set conventions of ``Linf``/``W1inf`` do not matter: the
    maxima of a P1 function are attained at vertices.  ``plus``/``minus`` parts are not supported.
    """
    from signorini.norms import Conventions, parse_norm

    conv = conventions or Conventions()
    p, t = mesh.p, mesh.t
    v = np.asarray(v, dtype=float)
    scale = float(np.abs(v).max(initial=0.0))
    out: dict[str, float] = {}
    if scale == 0.0 or not np.isfinite(scale):
        for name in names:
            parse_norm(name)
            out[name] = 0.0 if scale == 0.0 else math.nan
        return out
    w = v / scale  # normalised: no under-/overflow in high powers
    w0, w1, w2 = w[t[0]], w[t[1]], w[t[2]]
    j00, j01 = p[0, t[1]] - p[0, t[0]], p[0, t[2]] - p[0, t[0]]
    j10, j11 = p[1, t[1]] - p[1, t[0]], p[1, t[2]] - p[1, t[0]]
    det = j00 * j11 - j01 * j10
    area = 0.5 * np.abs(det)
    d1, d2 = w1 - w0, w2 - w0
    g1 = (j11 * d1 - j10 * d2) / det
    g2 = (-j01 * d1 + j00 * d2) / det
    form = conv.w1p_form

    def power(q: float) -> float:
        return _triangle_power_integrals(w0, w1, w2, area, q)

    def boundary() -> tuple[float, float]:
        facets = mesh.facets[:, mesh.boundary_facets()]
        a, b = w[facets[0]], w[facets[1]]
        length = np.linalg.norm(p[:, facets[1]] - p[:, facets[0]], axis=0)
        l2 = math.sqrt(float(np.sum(length * (a * a + a * b + b * b) / 3.0)))
        semi = math.sqrt(float(np.sum((b - a) ** 2 / length)))
        return l2, semi

    for name in names:
        parse_norm(name)  # unknown names raise UnknownNormError
        m = re.fullmatch(r"(L|W1)(inf|\d+(?:\.\d+)?)", name)
        if name == "H1":
            value = math.sqrt(power(2) + float(np.sum(area * (g1**2 + g2**2))))
        elif name in ("H12", "L2boundary"):
            l2, semi = boundary()
            if name == "L2boundary":
                value = l2
            else:
                h1 = math.hypot(l2, semi) if conv.h12_form == "geometric_full" else semi
                value = math.sqrt(l2 * h1)
        elif m is None:
            raise ValueError(f"p1_norms: norm {name!r} is not supported (plus/minus parts)")
        elif m[1] == "L":
            value = 1.0 if m[2] == "inf" else power(float(m[2])) ** (1.0 / float(m[2]))
        elif m[2] == "inf":
            grad = np.hypot(g1, g2).max()
            if form == "components":
                value = max(1.0, float(np.abs(g1).max()), float(np.abs(g2).max()))
            else:
                value = float(grad) if form == "seminorm" else max(1.0, float(grad))
        else:
            q = float(m[2])
            if form == "components":
                integral = power(q) + float(np.sum(area * (np.abs(g1) ** q + np.abs(g2) ** q)))
            elif form == "gradient":
                integral = power(q) + float(np.sum(area * np.hypot(g1, g2) ** q))
            else:
                integral = float(np.sum(area * np.hypot(g1, g2) ** q))
            value = integral ** (1.0 / q)
        out[name] = scale * float(value)
    return out


# --- one measurement ------------------------------------------------------------------------


@dataclass
class Attempt:
    """The outcome of one solver call: result (or None), status, reason and timings."""

    result: Any
    status: str
    reason: str
    times: list[float]


@contextlib.contextmanager
def _solver_log(solver: str) -> Iterator[tuple[dict, Path | None]]:
    """Solver options that send the solver's log to a temporary file (HiGHS), and the file."""
    option = LOG_FILE_OPTIONS.get(solver)
    if option is None:
        yield {}, None
        return
    with tempfile.TemporaryDirectory(prefix="wp-log-") as tmp:
        path = Path(tmp) / "solver.log"
        yield {option: str(path)}, path


def _log_reason(path: Path | None) -> str:
    """The status lines of a solver log (e.g. HiGHS' ``Model status : Solve error`` and its ERROR line)."""
    if path is None or not path.exists():
        return ""
    keep = [
        " ".join(line.split())
        for line in path.read_text(errors="replace").splitlines()
        if re.search(r"error|model status", line, re.IGNORECASE)
    ]
    return "; ".join(dict.fromkeys(keep))[:300]


def classify_failure(err: BaseException, elapsed: float, time_limit_s: float | None) -> tuple[str, str]:
    """(status, reason) of a solver call that raised ``err`` after ``elapsed`` seconds."""
    message = " ".join(str(err).split())
    status = re.search(r"returned status '(\w+)'", message)
    if status and status[1] == "optimal_inaccurate":
        return "inaccurate", "solver status optimal_inaccurate (cvxpy_solve returns no solution for it)"
    if time_limit_s is not None and elapsed >= 0.9 * time_limit_s:
        return "failed", f"time limit ({time_limit_s:g} s)"
    if status and status[1] == "user_limit":
        return "failed", "iteration limit (status user_limit)"
    if status:
        return "failed", f"solver status {status[1]}"
    return "failed", f"{type(err).__name__}: {message[:240]}"


def run_solver(
    config: SolverConfig,
    disc,
    tol: float | None,
    time_limit_s: float | None = None,
    repeat_below_s: float = REPEAT_BELOW_S,
    repeats: int = REPEATS,
) -> Attempt:
    """Solve ``disc`` (a ``DiscreteProblem``) with ``config`` at tolerance ``tol`` (None: the
    solver's default; ignored by the active-set solver); never raises.

    Timing: wall time of the call; repeated (best of ``repeats``) when the first call takes
    less than ``repeat_below_s``.  The status compares the worst relative KKT residual with
    ``tol`` (or the solver's default tolerance, or the active-set certificate's 1e-10).
    """
    from signorini.discrete import solve_discrete
    from signorini.solvers import cvxpy_solve
    from signorini.solvers.cvxpy_qp import TOLERANCE_OPTIONS

    options = dict(config.options)
    limit = None if config.exact else time_limit_s
    if config.exact:
        warm = options.pop("warm_start", "cascade")
        required = float(options.get("kkt_tol", 1e-10))
    else:
        if limit is not None and config.solver in TIME_LIMIT_OPTIONS:
            options.setdefault(TIME_LIMIT_OPTIONS[config.solver], float(limit))
        default = TOLERANCE_OPTIONS.get(config.solver, ((), math.nan))[1]
        required = float(tol) if tol is not None else float(default)

    def call():
        if config.exact:
            return solve_discrete(disc, "active_set", warm_start=warm, **options)
        return cvxpy_solve(disc.A, disc.b, disc.boundary, config.solver, tol=tol, check=False, **options)

    times: list[float] = []
    result = None
    with _solver_log(config.solver) as (log_options, log_path):
        options.update(log_options)
        for k in range(repeats):
            t0 = time.perf_counter()
            try:
                result = call()
            except Exception as err:  # a failing solver is recorded, never raised
                elapsed = time.perf_counter() - t0
                status, reason = classify_failure(err, elapsed, limit)
                detail = _log_reason(log_path)
                if detail and "time limit" not in reason:  # the solver's own words instead of cvxpy's
                    reason = f"{reason.split(':')[0]}: {detail}"
                log.info("%s tol=%s: %s (%s) after %.2f s", config.name, tol, status, reason, elapsed)
                return Attempt(None, status, reason, [*times, elapsed])
            times.append(time.perf_counter() - t0)
            if k == 0 and times[0] >= repeat_below_s:
                break
    worst = result.certificate.worst
    if not np.isfinite(worst) or worst > required:
        return Attempt(result, "inaccurate", f"KKT residual {worst:.1e} > tolerance {required:.0e}", times)
    return Attempt(result, "ok", "", times)


def _warm_up(config: SolverConfig) -> None:
    """Load the solver's libraries with a 3-unknown QP, so the first timed call pays no import."""
    if config.exact:
        return
    import scipy.sparse as sp

    from signorini.solvers import cvxpy_solve

    with contextlib.suppress(Exception):
        A = sp.identity(3, format="csr") * 2.0
        cvxpy_solve(A, np.array([1.0, -1.0, 1.0]), np.array([0, 1]), config.solver, check=False, **config.options)


def tolerance_label(tol: float | None, config: SolverConfig) -> str:
    """``exact`` (active set), ``default`` (solver default) or the tolerance as ``1e-06``."""
    if config.exact:
        return EXACT_LABEL
    return "default" if tol is None else f"{tol:.0e}"


def planned_runs(config: SolverConfig, tolerances: Sequence[float]) -> list[float | None]:
    """The active set once; a QP solver at its default tolerance (None), then loose to tight."""
    if config.exact:
        return [None]
    return [None, *sorted({float(t) for t in tolerances}, reverse=True)]


def skip_reason(
    prev: Mapping | None, n: int, time_limit_s: float | None, exponent: float = GROWTH_EXPONENT
) -> str | None:
    """Why a run is skipped, judged from the same configuration and tolerance on the previous
    mesh (``prev``, a record): it was skipped or failed there, or its time scaled by
    ``(n / n_prev)^exponent`` exceeds ``time_limit_s``.  None: run it."""
    if prev is None:
        return None
    where = f"N={prev['N']}"
    if prev["status"] == "skipped":
        return str(prev["reason"]) if "at N=" in str(prev["reason"]) else f"{prev['reason']} at {where}"
    if prev["status"] == "failed":
        if str(prev["reason"]).startswith("time limit"):
            return f"time budget ({prev['reason']} hit at {where})"
        return f"failed at {where}: {prev['reason']}"
    if time_limit_s is None:
        return None
    predicted = float(prev["time_s"]) * (n / int(prev["n_dofs"])) ** exponent
    if predicted > time_limit_s:
        was = float(prev["time_s"])
        return f"time budget (predicted {predicted:.0f} s > {time_limit_s:g} s from {was:.1f} s at {where})"
    return None


def _fingerprint(u: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(u).tobytes()).hexdigest()


def measure_stage(
    problem_params: Mapping,
    N: int,
    config: Mapping,
    tolerances: Sequence[float],
    time_limit_s: float | None,
    system_npz: str | os.PathLike,
    system_json: str | os.PathLike,
    exact_npz: str | os.PathLike,
    disc_norm_jsons: Mapping[str, str | os.PathLike],
    out_json: str | os.PathLike,
    prev_json: str | os.PathLike | None = None,
    diagonal: str = "sw_ne",
    conventions: Mapping | None = None,
    growth_exponent: float = GROWTH_EXPONENT,
) -> dict:
    """Run one solver configuration (``SolverConfig.as_dict()``) on mesh ``N`` at its default
    and at every tolerance of ``tolerances``; save the records (see the module docstring).

    ``time_limit_s`` limits each QP solve (the solver's own option) and drives ``skip_reason``
    (for every configuration, the active-set ones included).
    ``disc_norm_jsons``: the source scene's norm artifacts of this ``N`` (norm → path), whose
    values are the discretisation errors and define the norms measured.  ``prev_json``: this
    configuration's artifact on the previous mesh, for ``skip_reason``.
    """
    from signorini.discrete import DiscreteProblem
    from signorini.mesh import friedrichs_keller, mesh_width
    from signorini.norms import Conventions, evaluate_norms
    from signorini.problem import Problem

    started, t_job = time.time(), time.perf_counter()
    load_start = os.getloadavg()[0]
    config = SolverConfig(**config)
    time_limit = float(time_limit_s) if time_limit_s is not None else None
    exponent = float(growth_exponent)
    problem = Problem(**{k: float(v) for k, v in problem_params.items()})
    conv = Conventions(**dict(conventions or {}))
    names = list(disc_norm_jsons)
    disc_err = {}
    for name, path in disc_norm_jsons.items():
        art = load_json(path)
        if art.get("norm") != name or int(art.get("N", -1)) != int(N):
            raise CorruptArtifactError(f"{path}: holds {art.get('norm')} at N={art.get('N')}, not {name} at N={N}")
        disc_err[name] = float(art["value"])
    mesh = friedrichs_keller(int(N), diagonal)
    A, b, boundary = load_system(system_npz)
    build_s = float(load_json(system_json)["build_s"])
    disc = DiscreteProblem(problem, int(N), diagonal, mesh, A, b, boundary)
    exact = load_npz(exact_npz)["u"]
    if exact.shape != b.shape:
        raise CorruptArtifactError(f"{exact_npz}: u has shape {exact.shape}, expected {b.shape} for N={N}")
    prev = {}
    if prev_json:
        prev = {r["tol_label"]: r for r in load_json(prev_json)["records"]}
    _warm_up(config)
    norm_cache: dict[str, dict[str, float]] = {_fingerprint(exact): disc_err}
    records = []
    for tol in planned_runs(config, tolerances):
        label = tolerance_label(tol, config)
        record: dict[str, Any] = {
            "N": int(N),
            "h": mesh_width(int(N)),
            "n_dofs": int(b.size),
            "config": config.name,
            "solver": config.solver,
            "label": config.label,
            "tol": math.nan if tol is None else float(tol),
            "tol_label": label,
            "is_default": tol is None and not config.exact,
            "load1": os.getloadavg()[0],
            "build_s": build_s,
        }
        skip = skip_reason(prev.get(label), int(b.size), time_limit, exponent)
        if skip is not None:
            record.update(status="skipped", reason=skip, time_s=math.nan, time_runs=0)
            record.update({f"disc_{n}": disc_err[n] for n in names})
            records.append(record)
            log.info("N=%d %s %s: skipped (%s)", N, config.name, label, skip)
            continue
        attempt = run_solver(config, disc, tol, time_limit)
        record.update(
            status=attempt.status,
            reason=attempt.reason,
            time_s=min(attempt.times) if attempt.result is not None else attempt.times[-1],
            time_runs=len(attempt.times),
            times=" ".join(f"{t:.6g}" for t in attempt.times),
        )
        res = attempt.result
        if res is not None:
            summary = res.summary()
            record.update(
                iterations=int(res.iterations),
                solver_time_s=float(summary.get("solve_time_s", math.nan)),
                n_active=int(res.active.size),
                **{f"kkt_{k}": float(v) for k, v in res.certificate.as_dict().items() if k not in ("ok", "tol")},
            )
            alg = p1_norms(mesh, res.u - exact, names, conv)
            key = _fingerprint(res.u)
            if key not in norm_cache:
                norm_cache[key] = evaluate_norms(problem, mesh, res.u, names, conv)
            record.update({f"alg_{n}": alg[n] for n in names})
            record.update({f"total_{n}": norm_cache[key][n] for n in names})
        record.update({f"disc_{n}": disc_err[n] for n in names})
        records.append(record)
        log.info(
            "N=%d %s %s: %s %s time %.3f s, L4 alg %.2e",
            N,
            config.name,
            label,
            record["status"],
            record["reason"],
            record["time_s"],
            record.get("alg_L4", math.nan),
        )
    info = {
        "N": int(N),
        "config": config.as_dict(),
        "tolerances": [float(t) for t in tolerances],
        "time_limit_s": time_limit,
        "growth_exponent": exponent,
        "records": records,
        "job": {
            "started": started,
            "wall_s": time.perf_counter() - t_job,
            "load1_start": load_start,
            "load1_end": os.getloadavg()[0],
            "note": "wall_s: perf_counter over the whole stage function (loading, warm-up, solves, norms)",
        },
    }
    for r in records:
        r["job_wall_s"] = info["job"]["wall_s"]
        r["job_started"] = started
    save_json(out_json, info)
    return info


# --- the table of all measurements ----------------------------------------------------------

ID_COLUMNS = [
    "N",
    "h",
    "n_dofs",
    "config",
    "solver",
    "label",
    "tol",
    "tol_label",
    "is_default",
    "status",
    "reason",
    "time_s",
    "time_runs",
    "times",
    "solver_time_s",
    "iterations",
    "n_active",
    "kkt_stationarity",
    "kkt_primal",
    "kkt_dual",
    "kkt_complementarity",
    "kkt_worst",
    "build_s",
    "job_wall_s",
    "job_started",
    "load1",
]


def collect_stage(jsons: Sequence[str | os.PathLike], out_csv: str | os.PathLike) -> pd.DataFrame:
    """``work_precision.csv``: every record of the measurement artifacts, one row each, columns
    ``ID_COLUMNS`` then ``alg_<norm>``, ``total_<norm>``, ``disc_<norm>`` (norm order kept)."""
    import pandas as pd

    rows = []
    for path in jsons:
        rows.extend(load_json(path)["records"])
    df = pd.DataFrame(rows)
    norms = [c.removeprefix("disc_") for c in df.columns if c.startswith("disc_")]
    columns = ID_COLUMNS + [f"{kind}_{n}" for kind in ("alg", "total", "disc") for n in norms]
    for c in columns:
        if c not in df.columns:
            df[c] = math.nan
    df = df[columns].sort_values(["N", "config"], kind="stable").reset_index(drop=True)
    buf = io.StringIO()
    df.to_csv(buf, index=False, lineterminator="\n")
    atomic_write_text(out_csv, buf.getvalue())
    return df


def read_measurements(path: str | os.PathLike) -> pd.DataFrame:
    """``work_precision.csv`` as a DataFrame (``reason``/``times`` as strings)."""
    import pandas as pd

    try:
        df = pd.read_csv(path, dtype={"reason": str, "times": str, "tol_label": str}, keep_default_na=True)
    except (OSError, ValueError) as err:
        raise CorruptArtifactError(f"{path}: unreadable CSV ({err})") from err
    df["reason"] = df["reason"].fillna("")
    return df
