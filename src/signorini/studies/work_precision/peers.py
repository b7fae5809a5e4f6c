"""How the work-precision study runs a PETSc peer (``signorini.peers``): under the timing protocol,
its answer certified and given the study's statuses like every other configuration's (``Attempt``);
without the interpreter, petsc4py or an inner solver, the runs are ``skipped`` with the reason."""

from __future__ import annotations

import numpy as np

from signorini.peers import PEER_FIELDS, PeerRoute, certified, driver_call, peer_info
from signorini.studies.work_precision.routes import Attempt
from signorini.studies.work_precision.study import SolverConfig, accuracy_status


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
    call = driver_call(route, config.solver, config.options, tol, time_limit_s, initial_guess)
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
    result = certified(answer, u, disc.A, disc.b, disc.boundary, tol, config.name)
    required = result.certificate.tol
    times = [float(t) for t in answer.get("solve_cpu_times", answer["solve_times"])]
    extra["kkt_required"] = required
    if not answer["converged"]:
        return Attempt(result, "failed", f"PETSc {answer['converged_reason']}", times, extra)
    status, reason = accuracy_status(result.certificate.worst, required)
    return Attempt(result, status, reason, times, extra)
