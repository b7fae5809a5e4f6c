"""PETSc's variational-inequality (SNES ``vinewtonrsls``, ``vinewtonssls``) and bound-constrained
(TAO ``tron``, ``gpcg``, ``bnls``, ``bqpip``, ``blmvm``) solvers as *peers*: solvers of the same
discrete problem that run outside this package.

They run as an external program, ``workflow/peers/petsc_peer.py`` (stdlib, numpy and petsc4py;
``pipeline.paths.PEER_DRIVER``), under an interpreter that has petsc4py (default ``PEER_PYTHON``,
``/usr/bin/python3`` with Debian's ``python3-petsc4py-real``): it reads a cached ``system.npz`` and
writes the solution and PETSc's own account (converged reason, iterations, setup and solve times,
the solver types it actually used).  This module probes the driver (``probe``), starts it
(``driver_call``) and turns its answer into a ``SolveResult`` certified like every other answer
(``certified``: ``solvers.certificate.kkt_certificate`` with ``λ = (Au − b)_B``).  When the
interpreter or petsc4py is missing, or PETSc lacks an inner solver (hypre, MUMPS, CHOLMOD), the probe
or the answer says why.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

# the routes of the peers, solver name → the kind of PETSc object the driver builds
PEER_SOLVERS = {"petsc_snes": "snes", "petsc_tao": "tao"}
PEER_PYTHON = "/usr/bin/python3"  # Debian's python3-petsc4py-real is built for it
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
            [python, str(driver), "probe"],
            capture_output=True,
            encoding="utf-8",
            timeout=PROBE_TIMEOUT_S,
            env=driver_environment(),
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


def driver_environment() -> dict[str, str]:
    """The driver's environment: the one every job computes in (``pipeline.jobenv``: one BLAS/OpenMP
    thread, no oversubscription; freed memory reused)."""
    from signorini.pipeline.jobenv import job_environment

    return job_environment(dict(os.environ))


def _last_line(text: str) -> str:
    lines = [" ".join(line.split()) for line in text.splitlines() if line.strip()]
    return (lines[-1] if lines else "no output")[:300]


def driver_call(
    route: PeerRoute,
    solver: str,
    options: Mapping[str, Any],
    tol: float | None,
    time_limit_s: float | None,
    initial_guess: np.ndarray | None = None,
):
    """A callable for ``timing.Timer``: one run of the driver (one solve of ``solver``, a name of
    ``PEER_SOLVERS``, with PETSc's ``options``), returning ``((answer, u), (solve wall s, solve CPU s))``
    — the driver's own timers around PETSc's ``solve`` — or ``((answer, None), None)`` when it gave no
    solution (timed from outside)."""
    request = {
        "kind": PEER_SOLVERS[solver],
        "options": dict(options),
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
                proc = subprocess.run(
                    command, capture_output=True, encoding="utf-8", timeout=timeout, env=driver_environment()
                )
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


def certified(answer: Mapping, u: np.ndarray, A, b: np.ndarray, B: np.ndarray, tol: float | None, name: str):
    """The ``SolveResult`` of a driver's solution ``u`` (an answer with status ``done``): the multiplier
    ``(Au − b)_B``, the contact set ``{i ∈ B: u_i ≤ 0}`` and the KKT certificate at ``tol`` (None:
    ``DEFAULT_TOL``, what PETSc's defaults must reach)."""
    from signorini.solvers.certificate import kkt_certificate
    from signorini.solvers.result import SolveResult

    required = DEFAULT_TOL if tol is None else float(tol)
    solve_s = float(answer["solve_s"])
    lam = (A @ u - b)[B]
    info = {"solve_time_s": solve_s, "setup_s": float(answer["setup_s"])}
    certificate = kkt_certificate(A, b, B, u, lam, required)
    return SolveResult(u, lam, B[u[B] <= 0.0], int(answer["iterations"]), solve_s, certificate, name, info)


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
