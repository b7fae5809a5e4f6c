"""Stage ``work_precision_measure``: one solver configuration (``study.SolverConfig``) on one mesh of
the source scene, at its default tolerance and at every swept one, timed under the timing protocol
(``signorini.timing``: CPU seconds per call, the median of its samples; for the exact routes the call
is ``solve_discrete`` with the cascade's coarse levels, for cvxpy ``cvxpy_solve`` with its
canonicalisation, for a PETSc peer its driver's ``solve`` plus, from the cascade start, the start's
cost).  Each answer is judged by the KKT certificate with the check disabled (an inaccurate answer is
recorded, not raised) and its algebraic error (exact norms of a P1 function) and total error (the
pipeline's conventions) are evaluated; a failure never raises, it is recorded with its reason, and a
run predicted to fail or to exceed the time limit from the previous mesh is skipped.  The records
are the rows of ``work_precision.csv`` (``table.Run``); what each column holds is described once, in
docs/work-precision.md (*Routes, kinds and the record of a run*; *The timing protocol*).
``table`` gathers the records, ``findings`` and ``report`` turn them into ``work_precision.md``,
``figures`` into the figures.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import re
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from signorini.fem.norms.p1 import p1_norms
from signorini.peers import PEER_PYTHON
from signorini.pipeline.artifacts import load_json, save_json
from signorini.studies.scene.store import SceneMesh, load_system, read_norm
from signorini.studies.work_precision.routes import Attempt
from signorini.studies.work_precision.study import (
    EXACT_LABEL,
    GROWTH_EXPONENT,
    SolverConfig,
    accuracy_status,
    table_solver,
)
from signorini.timing import CallFailed, Protocol, ReferenceKernel, Timer, machine_record

log = logging.getLogger(__name__)

def _log_reason(path: Path) -> str:
    """The status lines of a solver log (e.g. HiGHS' ``Model status : Solve error`` and its ERROR line)."""
    if not path.exists():
        return ""
    keep = [
        " ".join(line.split())
        for line in path.read_text(encoding="utf-8", errors="replace").splitlines()
        if re.search(r"error|model status", line, re.IGNORECASE)
    ]
    return "; ".join(dict.fromkeys(keep))[:300]


def classify_failure(err: BaseException, elapsed: float, time_limit_s: float | None) -> tuple[str, str]:
    """(status, reason) of a solver call that raised ``err`` after ``elapsed`` seconds (``err.status``:
    the solver's own status, ``solvers.NotConvergedError``)."""
    status = getattr(err, "status", None)
    if status == "optimal_inaccurate":
        return "inaccurate", "solver status optimal_inaccurate (cvxpy_solve returns no solution for it)"
    if time_limit_s is not None and elapsed >= 0.9 * time_limit_s:
        return "failed", f"time limit ({time_limit_s:g} s)"
    if status == "user_limit":
        return "failed", "iteration limit (status user_limit)"
    message = " ".join(str(err).split())
    return "failed", f"solver status {status}" if status else f"{type(err).__name__}: {message[:240]}"


def timed_call(
    config: SolverConfig,
    disc,
    tol: float | None,
    time_limit_s: float | None = None,
    peer=None,
    initial_guess: np.ndarray | None = None,
) -> Callable[[], tuple]:
    """The call ``run_solver`` times, for a round-robin of several configurations
    (``timing.round_robin``; ``benchmarks/``): in process ``(SolveResult, None)``; a peer
    ``((answer, u), (solve wall s, solve CPU s))`` (``signorini.peers.driver_call``, ``peers.outcome``)."""
    if config.peer:
        from signorini.peers import driver_call

        return driver_call(peer, config.solver, config.options, tol, time_limit_s, initial_guess)
    limit = None if config.exact else time_limit_s
    return config.runner.call(config, disc, tol, config.runner.settings(config, tol, limit)[0])


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


@dataclass
class _Inputs:
    """What every run of one job shares: the system, the exact solution, the discretisation errors,
    the previous mesh's records, the protocol's timer and reference kernel, the machine record
    (JSON), a peer's route (``signorini.peers.PeerRoute``) and the cascade's start (``_cascade_start``)."""

    disc: Any  # fem.discrete.DiscreteProblem
    exact: np.ndarray
    disc_err: dict[str, float]
    build_s: float
    prev: dict[str, dict]
    conventions: Any  # fem.norms.conventions.Conventions
    timer: Timer
    kernel: ReferenceKernel
    machine: str
    peer: Any = None
    start: np.ndarray | None = None
    start_timing: dict = field(default_factory=dict)


def _load_inputs(at: SceneMesh, config: SolverConfig, inputs: Mapping[str, Any], settings: Mapping) -> _Inputs:
    """What the job's runs share (``inputs`` and ``settings``: ``conventions``, ``timing``,
    ``peer_python``, see ``measure_stage``)."""
    from signorini.fem.discrete import DiscreteProblem
    from signorini.fem.norms.conventions import Conventions

    disc_err = {name: read_norm(path, name, at.N) for name, path in inputs["disc"].items()}
    A, b, boundary = load_system(inputs["system"], at.N)
    disc = DiscreteProblem(at.problem, at.N, at.diagonal, at.mesh(), A, b, boundary)
    prev_json = inputs.get("prev")
    prev = {r["tol_label"]: r for r in load_json(prev_json)["records"]} if prev_json else {}
    build_s = float(load_json(inputs["system_json"])["timings"]["build_s"])
    conventions = Conventions(**dict(settings["conventions"] or {}))
    timer, kernel = Timer(Protocol.from_mapping(settings["timing"])), ReferenceKernel(A)
    inp = _Inputs(disc, at.load_solution(inputs["exact"]), disc_err, build_s, prev, conventions, timer, kernel,
                  json.dumps(machine_record(), sort_keys=True))
    if config.peer:
        from signorini.peers import PeerRoute, probe

        python, driver = settings["peer_python"] or PEER_PYTHON, str(inputs["peer_driver"])
        inp.peer = PeerRoute(python, driver, str(inputs["system"]), probe(python, driver))
    return inp


def timed_start(disc: Any, timer: Timer, kernel: ReferenceKernel) -> tuple[np.ndarray | None, dict]:
    """The start of a configuration started from the cascade: the cascade's interpolated coarse
    solution of ``disc`` (``fem.solve.cascade_start``; None below its first coarse level), timed
    under the protocol, and the summary of its timing (empty without it)."""
    from signorini.fem.solve import cascade_start

    measured = timer.measure(lambda: (cascade_start(disc), None), kernel, accept=lambda u: True)
    if measured.result is None:
        return None, {}
    return measured.result, measured.summary(timer.protocol, timer.machine.cores)


def with_start(timing: Mapping, start: Mapping) -> dict:
    """A run's timing fields with the cost of its start (``timed_start``) added to ``time_s``,
    ``time_ref`` and ``wall_s`` and recorded (``start_s``, ``start_ref``): the start is part of the
    route, as the cascade's coarse levels are part of ours.  Unchanged without a start or a time."""
    if not start or "time_s" not in timing:
        return dict(timing)
    added = {key: timing[key] + start[key] for key in ("time_s", "time_ref", "wall_s")}
    return {**timing, "start_s": start["time_s"], "start_ref": start["time_ref"], **added}


def _cascade_start(inp: _Inputs, config: SolverConfig) -> str | None:
    """For a peer started from the cascade: its start (``inp.start``, ``inp.start_timing``); the
    reason to skip when the cascade has no coarse level at this N."""
    if not (config.peer and config.initial == "cascade"):
        return None
    from signorini.fem.solve import CASCADE_FACTOR, CASCADE_MIN_N

    inp.start, inp.start_timing = timed_start(inp.disc, inp.timer, inp.kernel)
    if inp.start is None:
        return f"no cascade start below N = {CASCADE_FACTOR * CASCADE_MIN_N} (the cascade solves cold there)"
    return None


def _base_record(inp: _Inputs, config: SolverConfig, tol: float | None) -> dict[str, Any]:
    from signorini.fem.mesh import mesh_width

    N = inp.disc.N
    return {
        "N": N,
        "h": mesh_width(N),
        "n_dofs": int(inp.disc.b.size),
        "config": config.name,
        "solver": table_solver(config.solver),
        "label": config.label,
        "tol": math.nan if tol is None else float(tol),
        "tol_label": tolerance_label(tol, config),
        "is_default": tol is None and not config.exact,
        "start": config.initial,
        "load1": os.getloadavg()[0],
        "build_s": inp.build_s,
        "machine": inp.machine,
    }


def run_solver(inp: _Inputs, config: SolverConfig, tol: float | None, time_limit_s: float | None) -> Attempt:
    """Solve the job's system with ``config`` at tolerance ``tol`` (None: the solver's default;
    ignored by the exact routes) under the timing protocol (``inp.timer``), a PETSc peer by its
    driver (``inp.peer``, from ``inp.start`` when given); never raises.  The status compares the
    worst relative KKT residual with the residual the route requires (``Runner.settings``)."""
    timer, kernel = inp.timer, inp.kernel
    if config.peer:
        from signorini.studies.work_precision.peers import run_peer

        return run_peer(config, inp.peer, inp.disc, tol, time_limit_s, timer, kernel, inp.start)
    limit = None if config.exact else time_limit_s
    options, required = config.runner.settings(config, tol, limit)
    option = config.runner.log_option(config)  # a log file: the solver's own words on a failure (HiGHS)
    with tempfile.TemporaryDirectory(prefix="wp-log-") as tmp:
        log_path = Path(tmp) / "solver.log"
        call = config.runner.call(config, inp.disc, tol, options | ({option: str(log_path)} if option else {}))
        try:
            measured = timer.measure(call, kernel)
        except CallFailed as err:  # a failing solver is recorded, never raised
            status, reason = classify_failure(err.error, err.elapsed, limit)
            detail = _log_reason(log_path)
            if detail and "time limit" not in reason:  # the solver's own words instead of cvxpy's
                reason = f"{reason.split(':')[0]}: {detail}"
            log.info("%s tol=%s: %s (%s) after %.2f s", config.name, tol, status, reason, err.elapsed)
            return Attempt(None, status, reason, [*(x.cpu_s for x in err.samples), err.elapsed])
    extra = {"timing": measured.summary(timer.protocol, timer.machine.cores), "kkt_required": required}
    status, reason = accuracy_status(measured.result.certificate.worst, required)
    return Attempt(measured.result, status, reason, [x.cpu_s for x in measured.samples], extra)


def _measure(inp: _Inputs, config: SolverConfig, tol: float | None, time_limit: float | None, norm_cache: dict) -> dict:
    """Run one (configuration, tolerance) and record its status, times, residuals and errors;
    a failed run's answer (a peer stopped by an iteration limit) gets residuals and algebraic
    errors, but no total errors: it is no candidate for Table 1."""
    from signorini.fem.norms.conventional import evaluate_norms

    names = list(inp.disc_err)
    attempt = run_solver(inp, config, tol, time_limit)
    times = attempt.times or [math.nan]
    extra = dict(attempt.extra)
    timing = with_start(extra.pop("timing", {}), inp.start_timing)
    record = {
        "status": attempt.status,
        "reason": attempt.reason,
        "time_s": times[-1],  # a failure without the protocol's summary: the time until it
        "time_runs": len(attempt.times),
        "times": " ".join(f"{t:.6g}" for t in attempt.times),
        **{k: v for k, v in timing.items() if v is not None},
        **extra,
    }
    res = attempt.result
    if res is not None:
        record.update(
            iterations=int(res.iterations),
            solver_time_s=float(res.summary().get("solve_time_s", math.nan)),
            n_active=int(res.active.size),
            **{f"kkt_{k}": float(v) for k, v in res.certificate.as_dict().items() if k not in ("ok", "tol")},
        )
        alg = p1_norms(inp.disc.mesh, res.u - inp.exact, names, inp.conventions)
        record.update({f"alg_{n}": alg[n] for n in names})
        if attempt.status == "failed":
            return record
        key = _fingerprint(res.u)
        if key not in norm_cache:
            norm_cache[key] = evaluate_norms(inp.disc.problem, inp.disc.mesh, res.u, names, inp.conventions)
        record.update({f"total_{n}": norm_cache[key][n] for n in names})
    return record


def _job_info(at, config, tolerances, time_limit, growth_exponent, inp: _Inputs, records: list, clock) -> dict:
    """The measurement artifact: the records (with the job's wall time), the protocol, the job."""
    started, t_job, load_start = clock
    wall_s = time.perf_counter() - t_job
    for r in records:
        r["job_wall_s"], r["job_started"] = wall_s, started
    return {
        "N": at.N,
        "config": config.as_dict(),
        "tolerances": [float(t) for t in tolerances],
        "time_limit_s": time_limit,
        "growth_exponent": float(growth_exponent),
        "records": records,
        **({"peer": inp.peer.probe} if inp.peer is not None else {}),
        "timing": {
            "protocol": inp.timer.protocol.as_dict(),
            "max_load": inp.timer.max_load,
            "cores": inp.timer.machine.cores,
            "kernel": inp.kernel.description,
            "waited_s": inp.timer.waited_s,
            **({"start": inp.start_timing} if inp.start_timing else {}),
        },
        "job": {
            "started": started,
            "wall_s": wall_s,
            "load1_start": load_start,
            "load1_end": os.getloadavg()[0],
            "note": "wall_s: perf_counter over the whole stage function (loading, warm-up, solves, norms)",
        },
    }


def measure_stage(
    at: SceneMesh,
    config: Mapping,
    tolerances: Sequence[float],
    time_limit_s: float | None,
    inputs: Mapping[str, Any],
    out_json: str | os.PathLike,
    conventions: Mapping | None = None,
    growth_exponent: float = GROWTH_EXPONENT,
    peer_python: str | None = None,
    timing: Mapping | None = None,
) -> dict:
    """Stage ``work_precision_measure``: run one solver configuration (``SolverConfig.as_dict()``)
    on one mesh of the scene (``at``) at its default and at every tolerance of ``tolerances``; save
    the records (see the module docstring).

    ``inputs``: ``system`` and ``system_json`` (the source scene's ``discretise`` artifacts),
    ``exact`` (its solution), ``disc`` (its norm artifacts of this mesh, norm → path: the
    discretisation errors, which also define the norms measured) and ``prev`` (this
    configuration's artifact on the previous mesh, or None, for ``skip_reason``).
    ``time_limit_s`` limits each QP solve (the solver's own option; a peer's process is killed
    after it plus ``signorini.peers.START_SLACK_S``) and drives ``skip_reason`` (for every configuration,
    the active-set ones included).  A PETSc peer runs ``inputs["peer_driver"]`` under
    ``peer_python``; its probe (PETSc version, inner solvers) is saved with the records.
    ``timing``: the timing protocol's parameters (``timing.Protocol``; the study's ``timing`` block).
    A peer started from the cascade gets its start once per job (``_cascade_start``)."""
    started, t_job, load_start = time.time(), time.perf_counter(), os.getloadavg()[0]
    config = SolverConfig(**config)
    time_limit = float(time_limit_s) if time_limit_s is not None else None
    settings = {"conventions": conventions, "timing": timing, "peer_python": peer_python}
    inp = _load_inputs(at, config, inputs, settings)
    config.runner.warm_up(config)  # a peer starts a fresh process per run anyway
    no_start = _cascade_start(inp, config)
    norm_cache: dict[str, dict[str, float]] = {_fingerprint(inp.exact): inp.disc_err}
    records = []
    for tol in planned_runs(config, tolerances):
        record = _base_record(inp, config, tol)
        prev = inp.prev.get(record["tol_label"])
        skip = no_start or skip_reason(prev, record["n_dofs"], time_limit, float(growth_exponent))
        if skip is not None:
            record.update(status="skipped", reason=skip, time_s=math.nan, time_runs=0)
        else:
            record.update(_measure(inp, config, tol, time_limit, norm_cache))
        record.update({f"disc_{n}": v for n, v in inp.disc_err.items()})
        records.append(record)
        log.info("N=%d %s %s: %s %s time %.3f s, L4 alg %.2e", at.N, config.name, record["tol_label"],
                 record["status"], record["reason"], record["time_s"], record.get("alg_L4", math.nan))
    info = _job_info(at, config, tolerances, time_limit, growth_exponent, inp, records, (started, t_job, load_start))
    save_json(out_json, info)
    return info
