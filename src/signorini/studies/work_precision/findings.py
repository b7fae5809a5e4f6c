"""Findings of the work-precision study: what ``work_precision.md`` states, in numbers
(``findings``), computed from the runs of the measurement table (``table.Run``) through one
selection rule (``selection``) and the intervals of ``intervals``; ``report`` renders them.

Times are ranked and divided in CPU seconds (``time_s``), not in the reference units
(``time_ref``): on this machine the reference kernel's time varies from sample to sample about as
much as a call's, even within one round-robin, so dividing by it adds that noise; beside busy
processes it kept the ratios no better than CPU times did (``docs/evidence/timing_robustness*.json``).
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from signorini import intervals
from signorini.studies.work_precision.routes import Kind
from signorini.studies.work_precision.selection import (
    digits_unchanged,
    keeps_digits,
    printed,
    selected_tolerances,
    table1_norms_of,
)
from signorini.studies.work_precision.study import EXACT_LABEL
from signorini.studies.work_precision.table import Run, sweeps
from signorini.timing import Protocol

STOPS = ("spread", "budget", "max_repeats", "answer rejected")  # ``time_stop``: why a run's sampling ended
NAN = math.nan
COST_NORMS = ("L4", "W14")  # the norms of the exact solver's cost of accuracy


def _time(run: Run | None) -> dict:
    """A run's time with its interval (``intervals``) and its number of samples; NaN without a run."""
    if run is None or not math.isfinite(run.time_s):
        return {"value": NAN, "lo": NAN, "hi": NAN, "interval": False, "samples": 0}
    return {**run.time_estimate().summary(), "samples": int(intervals.samples(run.times).size)}


def _cell_changes(runs: Sequence[Run], Ns: Sequence[int], t1: Sequence[str], chosen: Mapping) -> list[dict]:
    """Per (config, tolerance): Table 1 cells printed differently, worst relative change, statuses,
    the meshes on which the run keeps Table 1's digits, whether it is the selected tolerance."""
    cells = []
    for (config, label), by in sweeps(runs).items():
        answered = [by[N] for N in Ns if N in by and digits_unchanged(by[N], t1) is not None]
        cells_of = [(run.total[n], run.disc[n]) for run in answered for n in t1]
        last = by.get(Ns[-1])
        cells.append(
            {
                "config": config,
                "label": next(iter(by.values())).label,
                "tol_label": label,
                "answered": len(answered) == len(Ns),
                "changed": sum(printed(total) != printed(disc) for total, disc in cells_of),
                "n_cells": len(t1) * len(Ns),
                "worst_rel_change": max([0.0, *(abs(total / disc - 1.0) for total, disc in cells_of)]),
                "keeping": sum(keeps_digits(run, t1) for run in answered),
                "selected": chosen.get(config) == label,
                "statuses": [by[N].status if N in by else "—" for N in Ns],
                "time_last": _time(last),
                "alg_L4_rel_last": last.alg["L4"] / last.disc["L4"] if last is not None else NAN,
            }
        )
    return cells


class Selected:
    """The selected runs (``selection``): ``tolerance`` per configuration, ``run[(config, N)]`` and
    its time's bootstrap ``est[(config, N)]`` (``Run.time_estimate``)."""

    def __init__(self, runs: Sequence[Run], t1: Sequence[str]):
        self.tolerance = selected_tolerances(runs, t1)
        self.run = {(r.config, r.N): r for r in runs if self.tolerance.get(r.config) == r.tol_label}
        self.est = {key: r.time_estimate() for key, r in self.run.items()}

    def at(self, N: int, configs: Sequence[str] | None = None) -> dict[str, intervals.Estimate]:
        """Config → time estimate of the selected runs at ``N`` (of ``configs``, default all)."""
        return {c: e for (c, n), e in self.est.items() if n == N and (configs is None or c in configs)}

    def entry(self, config: str, N: int) -> dict:
        """The selected run's tolerance and time (``_time``)."""
        return {"config": config, "tol_label": self.tolerance[config], **_time(self.run[(config, N)])}


def _ratio(num: intervals.Estimate, den: intervals.Estimate) -> dict:
    r = intervals.ratio(num, den)
    return {**r.summary(), "verdict": intervals.verdict(r)}


def _fastest(sel: Selected, N: int) -> list[dict]:
    """The selected runs at ``N`` by median time, each with its ratio to the fastest."""
    at = sel.at(N)
    ranked = sorted(at, key=lambda c: at[c].value)
    return [
        {**sel.entry(c, N), "vs_fastest": _ratio(at[c], at[ranked[0]]) if k else None} for k, c in enumerate(ranked)
    ]


def _fair_race(runs: Sequence[Run], Ns: Sequence[int], sel: Selected) -> dict[str, list[dict]]:
    """Per N, two comparisons of our fastest exact configuration (direct or multigrid route) with
    the fastest other configuration, both by their selected runs' median times: ``same_warm_start``
    — ours from the cascade against the solvers started from the cascade's interpolated coarse
    solution (the start's cost included) — and ``cold_against_cold`` — ours from the cold start
    against the others from u = 0.  The ratio (other / ours) with its interval and verdict; empty
    without the selected runs of a side."""
    side = {r.config: (r.start, r.kind is Kind.EXACT) for r in runs if sel.tolerance.get(r.config)}
    out: dict[str, list[dict]] = {}
    for key, start in (("same_warm_start", "cascade"), ("cold_against_cold", "cold")):
        ours = [c for c, s in side.items() if s == (start, True)]
        others = [c for c, s in side.items() if s == (start, False)]
        if not ours or not others:
            continue
        out[key] = []
        for N in Ns:
            mine, theirs = sel.at(N, ours), sel.at(N, others)
            if mine and theirs:
                a, b = min(mine, key=lambda c: mine[c].value), min(theirs, key=lambda c: theirs[c].value)
                ratio = _ratio(theirs[b], mine[a])
                out[key].append({"N": N, "ours": sel.entry(a, N), "other": sel.entry(b, N), "ratio": ratio})
    return out


def _scaling(Ns: Sequence[int], sel: Selected) -> dict[str, dict]:
    """Per configuration with a selected tolerance: the exponent ``p`` of ``time ∝ unknowns^p``,
    least squares through its selected runs on every mesh, with its interval."""
    return {
        config: intervals.exponent([float(sel.run[(config, N)].n_dofs) for N in Ns], [sel.est[(config, N)] for N in Ns])
        .summary()
        for config, label in sel.tolerance.items()
        if label is not None
    }


def _l4_eocs(
    runs: Sequence[Run], Ns: Sequence[int], paper_rates: Sequence[float] | None, paper_l4: Mapping[int, float] | None
) -> list[dict]:
    """Per (config, tolerance) with an answer on every mesh (whatever its status: the question is
    what inexact solves do to the EOCs): the ``L⁴`` EOCs and their largest deviations from the
    published and from the exact EOCs."""
    from signorini.fem.convergence import eoc

    h = np.array([1.0 / N for N in Ns])
    paper = np.asarray(paper_rates) if paper_rates and np.isfinite(paper_rates).any() else None
    eocs = []
    for (config, label), by in sweeps(runs).items():
        e = np.array([by[N].total["L4"] if N in by else NAN for N in Ns])
        if len(Ns) < 2 or not np.all(np.isfinite(e)):
            continue
        rates = eoc(h, e)[1:]
        entry = {"config": config, "label": by[Ns[0]].label, "tol_label": label, "eoc": rates.tolist()}
        entry["max_dev_paper"] = float(np.nanmax(np.abs(rates - paper))) if paper is not None else NAN
        if paper_l4:
            entry["l4_dev_paper"] = [
                float(e[k] / paper_l4[N] - 1.0) if N in paper_l4 else NAN for k, N in enumerate(Ns)
            ]
        eocs.append(entry)
    exact = next((np.asarray(x["eoc"]) for x in eocs if x["tol_label"] == EXACT_LABEL), None)
    for entry in eocs:
        entry["max_dev_exact"] = float(np.max(np.abs(np.asarray(entry["eoc"]) - exact))) if exact is not None else NAN
    return eocs


def _exact_cost(Ns: Sequence[int], sel: Selected) -> dict[str, Any]:
    """The first exact configuration's selected runs: assembly and solve times per N, total errors,
    and the slope of log error against log total time (assembly + solve) with its interval and the
    time factor per digit, ``10^(−1/slope)``."""
    first = next((c for c, lab in sel.tolerance.items() if lab == EXACT_LABEL), None)
    if first is None:
        return {}
    runs = [sel.run[(first, N)] for N in Ns]
    build = [r.build_s for r in runs]
    total = [intervals.shifted(sel.est[(first, N)], b) for N, b in zip(Ns, build, strict=True)]
    exact = {
        "config": first,
        "label": runs[0].label,
        "N": list(Ns),
        "build_s": build,
        "time": [_time(r) for r in runs],
        "total_time": [t.summary() for t in total],
    }
    for n in COST_NORMS:
        if n in runs[0].total and len(runs) >= 2:
            err = [r.total[n] for r in runs]
            slope = intervals.exponent(total, err).summary()
            factor = {k: 10.0 ** (-1.0 / slope[k]) if slope[k] < 0 else math.inf for k in ("value", "lo", "hi")}
            exact |= {f"total_{n}": err, f"slope_{n}": slope, f"time_factor_per_digit_{n}": factor}
    return exact


def _closest_l4(runs: Sequence[Run], paper_l4: Mapping[int, float] | None) -> dict[int, dict]:
    """Per N with a published ``L⁴`` cell, the run whose total ``L⁴`` error is closest to it."""
    closest: dict[int, dict] = {}
    for N, published in (paper_l4 or {}).items():
        rows = [r for r in runs if r.N == N and np.isfinite(r.total["L4"])]
        if not rows:
            continue
        dev = np.array([r.total["L4"] for r in rows]) / published - 1.0
        k = int(np.argmin(np.abs(dev)))
        exact = [r for r in rows if r.tol_label == EXACT_LABEL]
        closest[int(N)] = {
            "paper": float(published),
            "label": rows[k].label,
            "tol_label": rows[k].tol_label,
            "status": rows[k].status,
            "value": rows[k].total["L4"],
            "dev": float(dev[k]),
            "exact_dev": float(exact[0].total["L4"] / published - 1.0) if exact else NAN,
        }
    return closest


def _peers(runs: Sequence[Run]) -> dict[str, dict]:
    """Per PETSc peer configuration: its label, the statuses of all its runs, PETSc's reasons."""
    out = {}
    for config in dict.fromkeys(r.config for r in runs if r.kind is Kind.PEER):
        mine = [r for r in runs if r.config == config]
        out[config] = {
            "label": mine[0].label,
            "statuses": dict(Counter(r.status for r in mine)),
            "reasons": sorted({r.converged_reason for r in mine if r.converged_reason}),
        }
    return out


RESIDUALS = ("stationarity", "primal", "dual", "complementarity")  # the certificate's, as the CSV names them


def _stop_disagreements(runs: Sequence[Run]) -> list[dict]:
    """Per peer configuration, the runs where PETSc's own stopping test and our certificate disagree:
    ``converged`` — PETSc reported convergence (its reasons), the certificate rejects the answer,
    with the range of the largest residual and which residual it was in most of them; ``accepted``
    — PETSc stopped at a limit (``failed``), the certificate accepts the answer at the run's
    tolerance (its largest residual)."""
    out = []
    for config in dict.fromkeys(r.config for r in runs if r.kind is Kind.PEER):
        mine = [r for r in runs if r.config == config and math.isfinite(r.kkt_worst)]
        rejected = [r for r in mine if r.status == "inaccurate" and r.converged_reason.startswith("CONVERGED")]
        accepted = [r for r in mine if r.status == "failed" and r.kkt_worst <= r.kkt_required]
        if not (rejected or accepted):
            continue
        worst = Counter(max(RESIDUALS, key=lambda k: getattr(r, f"kkt_{k}")) for r in rejected)
        entry = {"config": config, "label": mine[0].label, "converged": len(rejected), "accepted": len(accepted)}
        if rejected:
            entry |= {"reasons": sorted({r.converged_reason for r in rejected}), "largest": worst.most_common(1)[0][0],
                      "lo": min(r.kkt_worst for r in rejected), "hi": max(r.kkt_worst for r in rejected)}
        if accepted:
            entry |= {"limits": sorted({r.converged_reason for r in accepted}),
                      "accepted_worst": max(r.kkt_worst for r in accepted)}
        out.append(entry)
    return out


def _numbers(runs: Sequence[Run], name: str) -> np.ndarray:
    """A field of the runs as floats (a flag as 0/1; missing: NaN)."""
    return np.array([NAN if (v := getattr(r, name)) is None else float(v) for r in runs], dtype=float)


def kernel_spread(runs: Sequence[Run]) -> float:
    """The largest relative range (max − min) / median, over the meshes, of the reference kernel's
    CPU time between the jobs of one mesh (each job: the median over its runs): an upper estimate
    of how much the whole machine's speed changed between those jobs (the kernel's own noise
    included); NaN without two timed jobs on one mesh."""
    jobs: dict[tuple[int, str], list[float]] = {}
    for r in runs:
        if math.isfinite(r.ref_s):
            jobs.setdefault((r.N, r.config), []).append(r.ref_s)
    meshes: dict[int, list[float]] = {}
    for (N, _), refs in jobs.items():
        meshes.setdefault(N, []).append(float(np.median(refs)))
    ranges = [(max(v) - min(v)) / float(np.median(v)) for v in meshes.values() if len(v) > 1 and np.median(v) > 0]
    return max(ranges) if ranges else NAN


def _protocol(runs: Sequence[Run], protocol: Protocol) -> dict[str, Any]:
    """What the timing protocol did: why each timed run's sampling stopped (``time_stop``), how many
    samples the runs with an answer have, the median relative spread of their samples (runs with
    two or more), overall and for the runs short enough that the budget holds ``min_repeats``
    samples; calls per sample, samples rejected and redone, runs accepted under load, CPU share."""
    timed = [r for r in runs if r.status != "skipped"]
    stop = [r.time_stop for r in timed]
    answered = [r for r in timed if r.status in ("ok", "inaccurate")]
    counts = np.array([intervals.samples(r.times).size for r in answered], dtype=int)
    spread, seconds = _numbers(answered, "spread"), _numbers(answered, "time_s")
    several = counts >= 2
    short_s = protocol.budget_s / protocol.min_repeats

    def median(values: np.ndarray) -> float:
        return float(np.median(values)) if values.size else NAN

    share, calls = _numbers(timed, "cpu_share"), _numbers(timed, "calls")
    return {
        "timed": len(stop) - stop.count(""),
        "stops": {k: stop.count(k) for k in STOPS},
        "raised": stop.count(""),  # failed at the first call, before any summary
        "answered": int(counts.size),
        "samples": {int(k): int(v) for k, v in zip(*np.unique(counts, return_counts=True), strict=True)},
        "samples_min": int(counts.min()) if counts.size else 0,
        "samples_median": median(counts.astype(float)),
        "samples_max": int(counts.max()) if counts.size else 0,
        "few": int((counts < protocol.min_repeats).sum()),
        "single": int((counts == 1).sum()),
        "spread_median": median(spread[several]),
        "several": int(several.sum()),
        "short_s": short_s,
        "spread_median_short": median(spread[several & (seconds < short_s)]),
        "short": int((several & (seconds < short_s)).sum()),
        "calls_max": float(np.nanmax(calls)) if np.isfinite(calls).any() else 1.0,
        "rejected": int(np.nansum(_numbers(timed, "rejected"))),
        "loaded": int(np.nansum(_numbers(timed, "loaded"))),
        "cpu_share_median": float(np.nanmedian(share)) if np.isfinite(share).any() else NAN,
        "kernel_spread": kernel_spread(timed),
    }


def concurrent_jobs(starts: np.ndarray, ends: np.ndarray) -> int:
    """The largest number of the intervals ``[starts[k], ends[k])`` that overlap at one instant."""
    keep = np.isfinite(starts) & np.isfinite(ends)
    # an end sorts before a start at the same instant: back-to-back jobs do not overlap
    events = sorted([(t, 1) for t in starts[keep]] + [(t, -1) for t in ends[keep]], key=lambda e: (e[0], e[1]))
    running = peak = 0
    for _, step in events:
        running += step
        peak = max(peak, running)
    return peak


def _software(runs: Sequence[Run]) -> dict[str, Any]:
    """What the table records of the machine and the software: the PETSc versions of the peers'
    runs (``peer_info``), and the distinct machine records (``machine``, JSON; empty in a table
    measured before it was recorded) with the number of runs of each."""
    petsc = sorted({r.peer_info.split(":")[0] for r in runs if r.peer_info.startswith("PETSc")})
    records = [r.machine for r in runs if r.machine.strip()]
    machines = [{"record": json.loads(text), "runs": records.count(text)} for text in dict.fromkeys(records)]
    return {"petsc": petsc, "machines": machines, "unrecorded": len(runs) - len(records)}


def _machine(runs: Sequence[Run]) -> dict[str, Any]:
    """Load average at the measurements, wall-clock span of the jobs, their summed time, how many
    ran at once, status counts."""
    load = _numbers([r for r in runs if r.status != "skipped"], "load1")
    load = load[np.isfinite(load)]
    jobs = list({(r.N, r.config): r for r in runs}.values())  # a job's runs share its start and wall time
    started, wall = _numbers(jobs, "job_started"), _numbers(jobs, "job_wall_s")
    ends = started + wall
    return {
        "load": dict(min=float(load.min()), median=float(np.median(load)), max=float(load.max())) if load.size else {},
        "span_s": float(np.nanmax(ends) - np.nanmin(started)) if runs else NAN,
        "job_time_s": float(np.nansum(wall)),
        "concurrent_jobs": concurrent_jobs(started, ends),
        "counts": dict(Counter(r.status for r in runs)),
        "software": _software(runs),
    }


def findings(
    runs: Sequence[Run],
    table1_norms: Sequence[str],
    paper_l4: Mapping[int, float] | None = None,
    paper_l4_eoc: Mapping[int, float] | None = None,
    protocol: Protocol | None = None,
) -> dict:
    """The numbers ``work_precision.md`` states, computed from the runs of the measurement table:
    one entry per helper above (its docstring says what the entry holds).  Every time is a
    run's median with its interval, ``{value, lo, hi, interval, samples}``, every ratio
    ``{value, lo, hi, interval, verdict}`` (``intervals``); every time compared is a selected run
    (``selection``) at the selected tolerance of its configuration (``tolerance``; ``needed``: of the
    configurations that are not exact).  ``paper_l4`` (N → published ``L⁴`` error) and
    ``paper_l4_eoc`` (N → published EOC) are the columns the ``L⁴`` errors and EOCs are compared
    with; ``protocol`` the timing protocol the runs were measured under (default: its defaults)."""
    Ns = sorted({r.N for r in runs})
    t1 = table1_norms_of(runs, table1_norms)
    sel = Selected(runs, t1)
    exact_configs = {r.config for r in runs if r.kind is Kind.EXACT}
    paper_rates = [paper_l4_eoc.get(N, NAN) for N in Ns[1:]] if paper_l4_eoc else None
    return {
        "N": Ns,
        "table1_norms": t1,
        "cells": _cell_changes(runs, Ns, t1, sel.tolerance),
        "tolerance": sel.tolerance,
        "needed": {c: t for c, t in sel.tolerance.items() if c not in exact_configs},
        "selected": {N: {c: sel.entry(c, N) for c in sel.at(N)} for N in Ns},
        "fastest": _fastest(sel, Ns[-1]),
        "fair": _fair_race(runs, Ns, sel),
        "scaling": _scaling(Ns, sel),
        "peers": _peers(runs),
        "stop_disagreements": _stop_disagreements(runs),
        "eoc": _l4_eocs(runs, Ns, paper_rates, paper_l4),
        "paper_l4_eoc": paper_rates,
        "exact": _exact_cost(Ns, sel),
        "closest_l4": _closest_l4(runs, paper_l4),
        "protocol": _protocol(runs, protocol or Protocol()),
        **_machine(runs),
    }
