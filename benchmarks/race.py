"""Several solver configurations of the work-precision study on one assembled system, timed
round-robin under the timing protocol (``signorini.timing.round_robin``) and certified alike: what
``benchmarks/peers.py`` and ``benchmarks/timing_robustness.py`` run (``from race import race``).

Each configuration is called, judged and charged as the study's measurement does it
(``signorini.studies.work_precision.measure``): its call (``timed_call``), the residual its answer
must reach (its route's ``Runner.settings``), the classification of a failure
(``classify_failure``), a peer's answer (``peers.outcome``), and, for a configuration started from
the cascade (a peer's ``_ws`` variant), the start (``timed_start``, computed and timed once) whose
cost is added to its time (``with_start``), as the cascade's own coarse levels are part of our
solver's time.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from signorini import intervals
from signorini.studies.work_precision.measure import classify_failure, timed_call, timed_start, with_start
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


def _from_cascade(config: SolverConfig) -> bool:
    return config.initial == "cascade" and not config.exact


def race(
    disc,
    configs: Mapping[str, SolverConfig],
    tol: float | None,
    timer: Timer,
    route=None,
    time_limit_s: float | None = None,
    reference: str = REFERENCE,
) -> dict:
    """Time ``configs`` on ``disc`` round-robin (peers through ``route``, a ``signorini.peers.PeerRoute``)
    at tolerance ``tol``; per configuration the protocol's summary, status, agreement with the
    reference configuration's solution (max norm relative to ``‖u‖∞``) and the time ratios to it
    (``ratio_ref``: reference units, ``ratio_cpu``, ``ratio_wall``; ``ratio_cpu_interval``: the CPU
    ratio's bootstrap interval and verdict, ``signorini.intervals``)."""
    kernel = ReferenceKernel(disc.A)
    start, start_timing = None, {}
    if any(_from_cascade(c) for c in configs.values()):
        start, start_timing = timed_start(disc, timer, kernel)
    tasks = []
    for name, config in configs.items():
        config.runner.warm_up(config)
        if _from_cascade(config) and start is None:
            continue  # no coarse level at this N: the variant would repeat the cold run
        initial_guess = start if _from_cascade(config) else None
        call = _guarded(timed_call(config, disc, tol, time_limit_s, route, initial_guess))
        tasks.append(Task(name, call, kernel, accept=lambda r: not isinstance(r, Exception)))
    round_robin(timer, tasks)
    out = {}
    for t in tasks:
        config = configs[t.name]
        status, reason, u, iterations = _status(config, disc, tol, t.result)
        summary = task_summary(timer, t)
        out[t.name] = {
            "label": config.label,
            "start": config.initial,
            "status": status,
            "reason": reason,
            "iterations": iterations,
            **(with_start(summary, start_timing) if _from_cascade(config) else summary),
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
    for name, rec in out.items():
        for key, field in (("ratio_ref", "time_ref"), ("ratio_cpu", "time_s"), ("ratio_wall", "wall_s")):
            ok = ref is not None and field in rec and field in ref and ref[field] > 0
            rec[key] = rec[field] / ref[field] if ok else math.nan
        if math.isfinite(rec["ratio_cpu"]):
            ratio = intervals.ratio(cpu_time(name, rec), cpu_time(reference, ref))
            rec["ratio_cpu_interval"] = ratio.summary() | {"verdict": intervals.verdict(ratio)}


def cpu_time(name: str, rec: Mapping) -> intervals.Estimate:
    """A configuration's CPU time with its bootstrap (its samples, shifted by a start's cost)."""
    return intervals.median(intervals.samples(rec["times"]), (name,), rec["time_s"])
