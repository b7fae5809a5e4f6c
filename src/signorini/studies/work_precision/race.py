"""Several solver configurations on one assembled system, timed round-robin under the timing
protocol (``timing.round_robin``) and certified alike: what ``benchmarks/peers.py`` and
``benchmarks/timing_robustness.py`` run.

A configuration started from the cascade (``SolverConfig.initial == "cascade"``, a peer's
``_ws`` variant) gets the cascade's interpolated coarse solution (``fem.solve.cascade_start``,
computed and timed once); its cost is added to the configuration's time, as the cascade's own
coarse levels are part of our solver's time.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from signorini.studies.work_precision.study import SolverConfig, accuracy_status
from signorini.timing import ReferenceKernel, Task, Timer, round_robin, task_summary

REFERENCE = "active_set"  # the reference solver of the ratios: our cascade active set


def _guarded(call):
    """``call`` with an exception returned as the result (a failing solver stops its task only)."""

    def run():
        try:
            return call()
        except Exception as err:  # recorded with the task
            return err, None

    return run


def _status(config: SolverConfig, disc, tol: float | None, result) -> tuple[str, str, np.ndarray | None, Any]:
    """(status, reason, u, iterations) of a task's last result, under our KKT certificate."""
    from signorini.studies.work_precision.measure import classify_failure
    from signorini.studies.work_precision.peers import outcome

    if isinstance(result, Exception):
        return (*classify_failure(result, 0.0, None), None, None)
    if config.peer:
        answer, u = result
        if u is None:
            return "failed", str(answer.get("reason", answer.get("status"))), None, None
        out = outcome(config, disc, tol, answer, u)
        return out.status, out.reason, out.result.u, out.result.iterations
    required = config.runner.settings(config, tol, None)[1]
    status, reason = accuracy_status(result.certificate.worst, required)
    return status, reason, result.u, int(result.iterations)


def race(
    disc,
    configs: Mapping[str, SolverConfig],
    tol: float | None,
    timer: Timer,
    route=None,
    time_limit_s: float | None = None,
    reference: str = REFERENCE,
) -> dict:
    """Time ``configs`` on ``disc`` round-robin (peers through ``route``, a ``peers.PeerRoute``)
    at tolerance ``tol``; per configuration the protocol's summary, status, agreement with the
    reference configuration's solution (max norm relative to ``‖u‖∞``) and the time ratios to it
    (``ratio_ref``: reference units, ``ratio_cpu``, ``ratio_wall``)."""
    from signorini.fem.solve import cascade_start
    from signorini.studies.work_precision.measure import timed_call

    kernel = ReferenceKernel(disc.A)
    start, start_timing = None, {}
    if any(c.initial == "cascade" and not c.exact for c in configs.values()):
        measured = timer.measure(lambda: (cascade_start(disc), None), kernel, accept=lambda u: True)
        start = measured.result
        start_timing = measured.summary(timer.protocol, timer.machine.cores) if start is not None else {}
    tasks = []
    for name, config in configs.items():
        config.runner.warm_up(config)
        warm = config.initial == "cascade" and not config.exact
        if warm and start is None:
            continue  # no coarse level at this N: the variant would repeat the cold run
        call = _guarded(timed_call(config, disc, tol, time_limit_s, route, start if warm else None))
        tasks.append(Task(name, call, kernel, accept=lambda r, c=config: not isinstance(r, Exception)))
    round_robin(timer, tasks)
    out = {}
    for t in tasks:
        config = configs[t.name]
        status, reason, u, iterations = _status(config, disc, tol, t.result)
        summary = task_summary(timer, t)
        if config.initial == "cascade" and not config.exact and "time_s" in summary:
            for key in ("time_s", "wall_s", "time_ref"):
                summary[key] += start_timing[key]
            summary["start_s"] = start_timing["time_s"]
        out[t.name] = {
            "label": config.label,
            "start": config.initial,
            "status": status,
            "reason": reason,
            "iterations": iterations,
            **summary,
            "_u": u,
        }
    _compare(out, reference)
    return {"configs": out, "start": start_timing, "kernel": kernel.description}


def _compare(out: dict, reference: str) -> None:
    """Agreement with the reference's solution and time ratios to it, in place (drops ``_u``)."""
    ref = out.get(reference)
    ref_u = ref["_u"] if ref else None
    for rec in out.values():
        u = rec.pop("_u")
        scale = float(np.abs(ref_u).max()) if ref_u is not None else math.nan
        rec["agreement"] = float(np.abs(u - ref_u).max()) / scale if u is not None and ref_u is not None else math.nan
    for rec in out.values():
        for key, field in (("ratio_ref", "time_ref"), ("ratio_cpu", "time_s"), ("ratio_wall", "wall_s")):
            ok = ref is not None and field in rec and field in ref and ref[field] > 0
            rec[key] = rec[field] / ref[field] if ok else math.nan
