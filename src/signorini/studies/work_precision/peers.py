"""PETSc's variational-inequality (SNES ``vinewtonrsls``, ``vinewtonssls``) and bound-constrained
(TAO ``tron``, ``gpcg``, ``bnls``, ``bqpip``, ``blmvm``) solvers as peers of the work-precision study.

They run as an external program, ``workflow/peers/petsc_peer.py`` (stdlib, numpy and petsc4py;
``pipeline.paths.PEER_DRIVER``), under an interpreter that has petsc4py (the study's
``peer_python``, default ``/usr/bin/python3`` with Debian's ``python3-petsc4py-real``): it reads
the cached ``system.npz`` of the source scene and writes the solution and PETSc's own account
(converged reason, iterations, setup and solve times, the solver types it actually used).  This
module starts it and turns its answer into a ``SolveResult`` certified like every other answer
(``solvers.certificate.kkt_certificate`` with ``λ = (Au − b)_B``), so the study treats the peers
exactly like its other configurations.  When the interpreter or petsc4py is missing, or PETSc
lacks an inner solver (hypre, MUMPS, CHOLMOD), the runs are ``skipped`` with that reason.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from signorini.studies.work_precision.routes import Attempt
from signorini.studies.work_precision.study import PEER_SOLVERS, SolverConfig, accuracy_status

DEFAULT_TOL = 1e-8  # PETSc's default snes_rtol and tao_gatol/grtol: what a default run must reach
PROBE_TIMEOUT_S = 120.0
START_SLACK_S = 60.0  # interpreter start, import and matrix set-up on top of the solve's time limit
# what a record keeps of the driver's answer; threads: the process's OS threads after the solve
PEER_FIELDS = ("petsc_version", "options", "effective", "python", "setup_times", "start", "threads")


@dataclass
class PeerRoute:
    """How to run the driver: interpreter, driver script, the system archive it reads, and what
    its probe found (``probe``)."""

    python: str
    driver: str
    system: str
    probe: dict = field(default_factory=dict)


def probe(python: str, driver: str | os.PathLike) -> dict:
    """The driver's ``probe`` under ``python``: PETSc version and inner solvers, or
    ``{"petsc4py": False, "error": why}`` for any failure to start the peer (interpreter missing
    or not executable, numpy or petsc4py not importable, the driver crashing, an answer that is
    not the probe's JSON): the peers are then unavailable, and their runs skipped with ``why``."""
    if not Path(python).exists():
        return _unavailable(f"peer interpreter {python} not found")
    try:
        proc = subprocess.run(
            [python, str(driver), "probe"], capture_output=True, encoding="utf-8", timeout=PROBE_TIMEOUT_S, env=_env()
        )
    except (OSError, subprocess.SubprocessError) as err:
        return _unavailable(f"peer interpreter {python}: {type(err).__name__}: {err}")
    where = f"{python} {Path(driver).name} probe"
    if proc.returncode != 0:
        return _unavailable(f"{where}: {_last_line(proc.stderr)}")
    try:
        found = json.loads(proc.stdout)
    except ValueError:
        found = None
    if not isinstance(found, dict) or "petsc4py" not in found:
        return _unavailable(f"{where}: not the probe's JSON answer: {_last_line(proc.stdout)}")
    if not found["petsc4py"]:
        found.setdefault("error", f"{where}: petsc4py unavailable (no reason given)")
    return found


def _unavailable(reason: str) -> dict:
    return {"petsc4py": False, "error": reason}


def _env() -> dict[str, str]:
    """The driver's environment: the one every job computes in (``pipeline.jobenv``: one BLAS/OpenMP
    thread, no oversubscription; freed memory reused)."""
    from signorini.pipeline.jobenv import job_environment

    return job_environment(dict(os.environ))


def _last_line(text: str) -> str:
    lines = [" ".join(line.split()) for line in text.splitlines() if line.strip()]
    return (lines[-1] if lines else "no output")[:300]


def driver_call(
    config: SolverConfig,
    route: PeerRoute,
    tol: float | None,
    time_limit_s: float | None,
    initial_guess: np.ndarray | None = None,
):
    """A callable for ``timing.Timer``: one run of the driver (one solve), returning
    ``((answer, u), (solve wall s, solve CPU s))`` — the driver's own timers around PETSc's
    ``solve`` — or ``((answer, None), None)`` when it gave no solution (timed from outside)."""
    request = {
        "kind": PEER_SOLVERS[config.solver],
        "options": dict(config.options),
        "tol": None if tol is None else float(tol),
        "repeat_below_s": 0.0,
        "repeats": 1,  # the repeats are the timing protocol's
    }
    timeout = None if time_limit_s is None else float(time_limit_s) + START_SLACK_S

    def call():
        with tempfile.TemporaryDirectory(prefix="wp-peer-") as name:
            tmp, req = Path(name), dict(request)
            if initial_guess is not None:
                np.savez(tmp / "start.npz", u=initial_guess)
                req["initial_guess"] = str(tmp / "start.npz")
            (tmp / "request.json").write_text(json.dumps(req), encoding="utf-8")
            command = [route.python, route.driver, "solve", route.system, str(tmp / "request.json"), name]
            try:
                proc = subprocess.run(command, capture_output=True, encoding="utf-8", timeout=timeout, env=_env())
            except subprocess.TimeoutExpired:
                return ({"status": "timeout", "reason": f"time limit ({time_limit_s:g} s)"}, None), None
            if proc.returncode != 0 or not (tmp / "result.json").exists():
                reason = f"driver exited {proc.returncode}: {_last_line(proc.stderr)}"
                return ({"status": "error", "reason": reason}, None), None
            answer = json.loads((tmp / "result.json").read_text(encoding="utf-8"))
            if answer.get("status") != "done":
                return (answer, None), None
            u = np.load(tmp / "solution.npz")["u"]
        return (answer, u), (float(answer["solve_s"]), float(answer.get("solve_cpu_s", answer["solve_s"])))

    return call


def run_peer(
    config: SolverConfig,
    route: PeerRoute,
    disc,
    tol: float | None,
    time_limit_s: float | None,
    timer,
    kernel,
    initial_guess: np.ndarray | None = None,
) -> Attempt:
    """Run ``config`` (a peer) at tolerance ``tol`` (None: PETSc's defaults) on ``route.system``
    under the timing protocol (``timer``, a ``timing.Timer``, with the reference ``kernel``),
    from u = 0 or from ``initial_guess``; certify its answer against ``disc`` (``A``, ``b``,
    ``boundary``).  Never raises."""
    from signorini.timing import CallFailed

    if not route.probe.get("petsc4py"):
        return Attempt(None, "skipped", str(route.probe.get("error", "")), [])
    call = driver_call(config, route, tol, time_limit_s, initial_guess)
    try:  # an answer that did not converge is not repeated
        measured = timer.measure(call, kernel, accept=lambda r: r[1] is not None and bool(r[0].get("converged")))
    except CallFailed as err:  # OSError starting the interpreter, a corrupt answer file, ...
        return Attempt(None, "failed", f"{type(err.error).__name__}: {err.error}"[:300], [err.elapsed])
    answer, u = measured.result
    timing = measured.summary(timer.protocol, timer.machine.cores)
    if answer.get("status") in ("timeout", "error"):  # no solve to time: the wall time until the end
        times = [measured.samples[-1].wall_s] if answer["status"] == "timeout" else []
        return Attempt(None, "failed", str(answer["reason"]), times, {"timing": {"load1": timing.get("load1")}})
    out = outcome(config, disc, tol, answer, u)
    out.extra["timing"] = timing
    return out


def outcome(config: SolverConfig, disc, tol: float | None, answer: dict, u) -> Attempt:
    """Status, certificate and record fields of a driver's answer: a ``SolveResult`` of its ``u``
    with the multiplier ``(Au − b)_B``, the contact set ``{i ∈ B: u_i ≤ 0}`` and the KKT certificate."""
    from signorini.solvers.certificate import kkt_certificate
    from signorini.solvers.result import SolveResult

    extra = {
        "setup_s": float(answer["setup_s"]) if "setup_s" in answer else float("nan"),
        "converged_reason": str(answer.get("converged_reason", "")),
        "peer_info": peer_info(answer),
        "peer": {k: answer.get(k) for k in PEER_FIELDS},
    }
    if answer.get("status") == "unavailable":
        return Attempt(None, "skipped", str(answer["reason"]), [], extra)
    if answer.get("status") != "done":
        return Attempt(None, "failed", str(answer.get("reason", answer.get("status"))), [], extra)
    required = DEFAULT_TOL if tol is None else float(tol)
    A, b, B, solve_s = disc.A, disc.b, disc.boundary, float(answer["solve_s"])
    lam = (A @ u - b)[B]
    info = {"solve_time_s": solve_s, "setup_s": float(answer["setup_s"])}
    certificate = kkt_certificate(A, b, B, u, lam, required)
    result = SolveResult(u, lam, B[u[B] <= 0.0], int(answer["iterations"]), solve_s, certificate, config.name, info)
    times = [float(t) for t in answer.get("solve_cpu_times", answer["solve_times"])]
    extra["kkt_required"] = required
    if not answer["converged"]:
        return Attempt(result, "failed", f"PETSc {answer['converged_reason']}", times, extra)
    status, reason = accuracy_status(result.certificate.worst, required)
    return Attempt(result, status, reason, times, extra)


def peer_info(answer: Mapping) -> str:
    """``PETSc 3.18.5: vinewtonrsls ksp=cg pc=hypre/boomeramg``: the version and the solver types
    PETSc actually used (what the CSV shows; the options are in the JSON records)."""
    eff = answer.get("effective") or {}
    if "petsc_version" not in answer:
        return ""
    pc = eff.get("pc_type")
    inner = eff.get("factor_solver_type") or eff.get("hypre_type")
    kinds = f" ksp={eff.get('ksp_type')} pc={pc}{'/' + inner if inner else ''}" if pc else ""
    return f"PETSc {answer['petsc_version']}: {eff.get('type', '')}{kinds}"
