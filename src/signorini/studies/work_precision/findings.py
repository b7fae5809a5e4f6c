"""Findings of the work-precision study: what ``work_precision.md`` states, in numbers.

Computed from the measurement table (``work_precision.csv``): how many Table 1 cells each
(solver, tolerance) changes in their printed 5 significant digits, the tolerance each solver
needs so that none changes, the fastest run per mesh that keeps them, the ``L⁴`` EOCs of the
inexact solutions against the published Table 2 column, the published ``L⁴`` cells each run
comes closest to, and the exact solver's cost per digit.  ``report`` renders them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from signorini.formatting import sci_md
from signorini.studies.work_precision.study import EXACT_LABEL
from signorini.studies.work_precision.table import tolerance_order

if TYPE_CHECKING:
    import pandas as pd


def printed(x: float) -> str:
    """A cell of Table 1 as printed (5 significant digits, ``formatting.sci_md``)."""
    return sci_md(x) if np.isfinite(x) else "—"


def _runs(df: pd.DataFrame, config: str, label: str) -> pd.DataFrame:
    """The rows of one (configuration, tolerance) indexed by N."""
    return df[(df["config"] == config) & (df["tol_label"] == label)].set_index("N")


def _unchanged(row: pd.Series, norms: Sequence[str]) -> bool | None:
    """Whether the run's total errors print like the exact ones in every Table 1 column
    (None: the run has no answer)."""
    if not norms or not np.isfinite(float(row[f"total_{norms[0]}"])):
        return None
    return all(printed(float(row[f"total_{n}"])) == printed(float(row[f"disc_{n}"])) for n in norms)


def _cell_changes(df: pd.DataFrame, Ns: Sequence[int], t1: Sequence[str]) -> list[dict]:
    """Per (config, tolerance): Table 1 cells printed differently, worst relative change, statuses."""
    cells = []
    for config, label in tolerance_order(df):
        sub = _runs(df, config, label)
        changed, worst, answered = 0, 0.0, True
        for N in Ns:
            row = sub.loc[N] if N in sub.index else None
            if row is None or _unchanged(row, t1) is None:
                answered = False
                continue
            for n in t1:
                ours, ref = float(row[f"total_{n}"]), float(row[f"disc_{n}"])
                changed += printed(ours) != printed(ref)
                worst = max(worst, abs(ours / ref - 1.0))
        last = sub.loc[Ns[-1]] if Ns[-1] in sub.index else None
        cells.append(
            {
                "config": config,
                "label": str(sub.iloc[0]["label"]),
                "tol_label": label,
                "exact": label == EXACT_LABEL,
                "answered": answered,
                "changed": changed,
                "n_cells": len(t1) * len(Ns),
                "worst_rel_change": worst,
                "statuses": [str(sub.loc[N, "status"]) if N in sub.index else "—" for N in Ns],
                "time_last": float(last["time_s"]) if last is not None else math.nan,
                "alg_L4_rel_last": (
                    float(last["alg_L4"] / last["disc_L4"]) if last is not None and "alg_L4" in sub else math.nan
                ),
            }
        )
    return cells


def _needed(cells: Sequence[Mapping]) -> dict[str, str | None]:
    """Per QP config, the loosest swept tolerance from which every tighter one keeps Table 1."""
    needed: dict[str, str | None] = {}
    for config in dict.fromkeys(c["config"] for c in cells if not c["exact"]):
        sweep = [c for c in cells if c["config"] == config and c["tol_label"] != "default"]
        sweep.sort(key=lambda c: float(c["tol_label"]))  # tight to loose
        best = None
        for c in sweep:
            if not (c["answered"] and c["changed"] == 0):
                break
            best = c["tol_label"]
        needed[config] = best
    return needed


# The column that ranks run times and forms their ratios: ``time_s``, CPU seconds under the timing
# protocol (wall seconds in tables measured before it).  Not the reference units ``time_ref``: on
# this machine the reference kernel's time varies from sample to sample about as much as a call's,
# even within one round-robin, so dividing by it adds that noise; beside busy processes it kept the
# ratios no better than CPU times did (``docs/evidence/timing_robustness*.json``).
RANK_KEY = "time_s"


def measured_under_protocol(df: pd.DataFrame) -> bool:
    """Whether the table was measured under the timing protocol (it has reference units)."""
    return "time_ref" in df.columns and bool(np.isfinite(df["time_ref"].to_numpy(dtype=float)).any())


def starts(df: pd.DataFrame) -> pd.Series:
    """Each row's start (``cascade`` or ``cold``); tables without the ``start`` column: the
    exact solver's cold configurations by their label, every other run cold."""
    import pandas as pd

    if "start" in df.columns and df["start"].notna().all():
        return df["start"].astype(str)
    exact = df["tol_label"] == EXACT_LABEL
    cold = df["label"].astype(str).str.contains("cold")
    return pd.Series(np.where(exact & ~cold, "cascade", "cold"), index=df.index)


def _cheapest(df: pd.DataFrame, Ns: Sequence[int], t1: Sequence[str]) -> dict[int, dict[str, dict]]:
    """Per N and config, the fastest run (by ``RANK_KEY``) that leaves Table 1's row of that N
    unchanged: its tolerance, its seconds and the value it is ranked by."""
    key = RANK_KEY
    cheapest: dict[int, dict[str, dict]] = {}
    for N in Ns:
        cheapest[N] = {}
        for config in dict.fromkeys(df["config"]):
            rows = df[(df["config"] == config) & (df["N"] == N)]
            good = [r for _, r in rows.iterrows() if _unchanged(r, t1)]
            if good:
                fastest = min(good, key=lambda r: float(r[key]))
                cheapest[N][config] = {
                    "tol_label": str(fastest["tol_label"]),
                    "time_s": float(fastest["time_s"]),
                    "rank": float(fastest[key]),
                }
    return cheapest


def _l4_eocs(
    df: pd.DataFrame, Ns: Sequence[int], paper_rates: Sequence[float] | None, paper_l4: Mapping[int, float] | None
) -> list[dict]:
    """Per (config, tolerance) with an answer on every mesh: the ``L⁴`` EOCs and their largest
    deviations from the published and from the exact EOCs."""
    from signorini.fem.convergence import eoc

    h = np.array([1.0 / N for N in Ns])
    eocs, exact_eoc = [], None
    for config, label in tolerance_order(df):
        sub = _runs(df, config, label)
        if "total_L4" not in sub.columns or len(Ns) < 2 or any(N not in sub.index for N in Ns):
            continue
        e = np.array([float(sub.loc[N, "total_L4"]) for N in Ns])
        if not np.all(np.isfinite(e)):
            continue
        rates = eoc(h, e)[1:]
        entry = {"config": config, "label": str(sub.iloc[0]["label"]), "tol_label": label, "eoc": rates.tolist()}
        entry["max_dev_paper"] = (
            float(np.nanmax(np.abs(rates - np.asarray(paper_rates))))
            if paper_rates and np.isfinite(paper_rates).any()
            else math.nan
        )
        if paper_l4:
            entry["l4_dev_paper"] = [
                float(e[k] / paper_l4[N] - 1.0) if N in paper_l4 else math.nan for k, N in enumerate(Ns)
            ]
        if label == EXACT_LABEL and exact_eoc is None:
            exact_eoc = rates
        eocs.append(entry)
    for entry in eocs:
        entry["max_dev_exact"] = (
            float(np.max(np.abs(np.asarray(entry["eoc"]) - exact_eoc))) if exact_eoc is not None else math.nan
        )
    return eocs


def _exact_cost(df: pd.DataFrame, Ns: Sequence[int]) -> dict[str, Any]:
    """The exact solver's times and total errors per N, and the slope of error against time."""
    exact_rows = df[df["tol_label"] == EXACT_LABEL]
    if exact_rows.empty:
        return {}
    first = exact_rows["config"].iloc[0]
    ex = exact_rows[exact_rows["config"] == first].set_index("N")
    ex = ex.loc[[N for N in Ns if N in ex.index]]
    total_time = (ex["build_s"] + ex["time_s"]).to_numpy(dtype=float)
    exact = {
        "config": first,
        "label": str(ex["label"].iloc[0]),
        "N": ex.index.tolist(),
        "build_s": ex["build_s"].tolist(),
        "time_s": ex["time_s"].tolist(),
        "total_time_s": total_time.tolist(),
    }
    for n in ("L4", "W14"):
        if f"total_{n}" in ex.columns and len(ex) >= 2:
            err = ex[f"total_{n}"].to_numpy(dtype=float)
            slope = float(np.polyfit(np.log10(total_time), np.log10(err), 1)[0])
            exact[f"total_{n}"] = err.tolist()
            exact[f"slope_{n}"] = slope
            exact[f"time_factor_per_digit_{n}"] = 10.0 ** (-1.0 / slope) if slope < 0 else math.inf
    return exact


def _closest_l4(df: pd.DataFrame, paper_l4: Mapping[int, float] | None) -> dict[int, dict]:
    """Per N with a published ``L⁴`` cell, the run whose total ``L⁴`` error is closest to it."""
    closest: dict[int, dict] = {}
    for N, published in (paper_l4 or {}).items() if "total_L4" in df.columns else ():
        rows = df[(df["N"] == N) & np.isfinite(df["total_L4"])]
        if rows.empty:
            continue
        dev = (rows["total_L4"] / published - 1.0).to_numpy(dtype=float)
        k = int(np.argmin(np.abs(dev)))
        exact_rows = rows[rows["tol_label"] == EXACT_LABEL]
        closest[int(N)] = {
            "paper": float(published),
            "label": str(rows["label"].iloc[k]),
            "tol_label": str(rows["tol_label"].iloc[k]),
            "status": str(rows["status"].iloc[k]),
            "value": float(rows["total_L4"].iloc[k]),
            "dev": float(dev[k]),
            "exact_dev": float(exact_rows["total_L4"].iloc[0] / published - 1.0) if len(exact_rows) else math.nan,
        }
    return closest


def is_peer(df: pd.DataFrame) -> pd.Series:
    """The rows of PETSc peers (``solver`` ``petsc_snes``/``petsc_tao``; none without the column)."""
    import pandas as pd

    if "solver" not in df.columns:
        return pd.Series(False, index=df.index)
    return df["solver"].astype(str).str.startswith("petsc_")


def _fit_exponent(n_dofs: Sequence[float], times: Sequence[float]) -> float:
    """Least-squares slope of log time against log unknowns (NaN with fewer than 2 points)."""
    if len(times) < 2:
        return math.nan
    return float(np.polyfit(np.log(np.asarray(n_dofs, dtype=float)), np.log(np.asarray(times, dtype=float)), 1)[0])


def _peers(df: pd.DataFrame, Ns: Sequence[int], t1: Sequence[str]) -> dict[str, Any]:
    """Our cascade against the PETSc peers: per N the fastest peer run that keeps Table 1's
    digits with status ``ok`` and its time over ours; per peer the time to those digits against
    the number of unknowns (fit ``time ∝ unknowns^p``)."""
    peers = df[is_peer(df)]
    exact = df[df["tol_label"] == EXACT_LABEL]
    if peers.empty or exact.empty:
        return {}
    ours_config = str(exact["config"].iloc[0])
    n_dofs = df.drop_duplicates("N").set_index("N")["n_dofs"]
    cheapest = _cheapest(df[df["status"] == "ok"], Ns, t1)
    names = list(dict.fromkeys(peers["config"]))
    ratio = []
    for N in Ns:
        ours = cheapest.get(N, {}).get(ours_config)
        runs = {c: v for c, v in cheapest.get(N, {}).items() if c in names}
        best = min(runs.items(), key=lambda kv: kv[1]["rank"]) if runs else None
        ratio.append(
            {
                "N": N,
                "ours_s": ours["time_s"] if ours else math.nan,
                "peer": best[0] if best else None,
                "peer_tol": best[1]["tol_label"] if best else None,
                "peer_s": best[1]["time_s"] if best else math.nan,
                "ratio": best[1]["rank"] / ours["rank"] if best and ours else math.nan,
            }
        )
    scaling = {}
    for config in names:
        points = [(N, float(n_dofs[N]), cheapest[N][config]) for N in Ns if config in cheapest.get(N, {})]
        rows = peers[peers["config"] == config]
        scaling[config] = {
            "label": str(rows["label"].iloc[0]),
            "N": [p[0] for p in points],
            "time_s": [p[2]["time_s"] for p in points],
            "tol_label": [p[2]["tol_label"] for p in points],
            "exponent": _fit_exponent([p[1] for p in points], [p[2]["time_s"] for p in points]),
            "statuses": rows["status"].value_counts().to_dict(),
            "reasons": sorted({str(r) for r in rows["converged_reason"] if str(r) and str(r) != "nan"}),
        }
    ours_rows = [r for r in ratio if math.isfinite(r["ours_s"])]
    return {
        "ours": ours_config,
        "ours_label": str(exact["label"].iloc[0]),
        "ours_exponent": _fit_exponent([float(n_dofs[r["N"]]) for r in ours_rows], [r["ours_s"] for r in ours_rows]),
        "ratio": ratio,
        "scaling": scaling,
        "any_ok": bool((peers["status"] == "ok").any()),
    }


def fastest_to_digits(df: pd.DataFrame, N: int, table1_norms: Sequence[str]) -> dict[str, dict]:
    """Per configuration, its fastest run at ``N`` that keeps Table 1's digits (the report's
    "fastest route to Table 1's digits")."""
    return _cheapest(df, [N], table1_norms)[N]


def _fastest(cheapest: Mapping, configs: Sequence[str]) -> tuple[str, dict] | None:
    runs = [(c, v) for c, v in cheapest.items() if c in configs]
    return min(runs, key=lambda kv: kv[1]["rank"]) if runs else None


def _fair_race(df: pd.DataFrame, Ns: Sequence[int], t1: Sequence[str]) -> dict[str, list[dict]]:
    """Per N, two comparisons of our fastest exact configuration (direct or multigrid route)
    with the fastest other solver to Table 1's digits (status ok): ``same_warm_start`` — ours
    from the cascade against the solvers started from the cascade's interpolated coarse
    solution (the start's cost included) — and ``cold_against_cold`` — ours from the cold
    start against the others from u = 0.  Ratios (other / ours) by ``RANK_KEY``; empty without
    the runs of a side."""
    start = starts(df)
    exact = df["tol_label"] == EXACT_LABEL
    cheapest = _cheapest(df[df["status"] == "ok"], Ns, t1)
    out: dict[str, list[dict]] = {}
    for key, kind in (("same_warm_start", "cascade"), ("cold_against_cold", "cold")):
        ours = list(dict.fromkeys(df.loc[exact & (start == kind), "config"]))
        others = list(dict.fromkeys(df.loc[~exact & (start == kind), "config"]))
        if not ours or not others:
            continue
        rows = []
        for N in Ns:
            mine, best = _fastest(cheapest.get(N, {}), ours), _fastest(cheapest.get(N, {}), others)
            rows.append(
                {
                    "N": N,
                    "ours": mine[0] if mine else None,
                    "ours_s": mine[1]["time_s"] if mine else math.nan,
                    "other": best[0] if best else None,
                    "other_tol": best[1]["tol_label"] if best else None,
                    "other_s": best[1]["time_s"] if best else math.nan,
                    "ratio": best[1]["rank"] / mine[1]["rank"] if best and mine else math.nan,
                }
            )
        out[key] = rows
    return out


def peer_comparison(df: pd.DataFrame, table1_norms: Sequence[str]) -> dict[str, Any]:
    """``findings(...)["peers"]`` alone (for the figures)."""
    Ns = sorted(int(N) for N in df["N"].unique())
    return _peers(df, Ns, [n for n in table1_norms if f"total_{n}" in df.columns])


def kernel_spread(df: pd.DataFrame) -> float:
    """The largest relative range (max − min) / median, over the meshes, of the reference kernel's
    CPU time between the jobs of one mesh (each job: the median over its runs): an upper estimate
    of how much the whole machine's speed changed between those jobs (the kernel's own noise
    included); NaN without two timed jobs on one mesh."""
    ref = pd_numeric(df, "ref_s")
    timed = df.assign(_ref=ref)[np.isfinite(ref)]
    per_job = timed.groupby(["N", "config"])["_ref"].median()
    ranges = [
        (float(v.max()) - float(v.min())) / float(v.median())
        for _, v in per_job.groupby(level="N")
        if len(v) > 1 and float(v.median()) > 0
    ]
    return max(ranges) if ranges else math.nan


def _protocol(df: pd.DataFrame) -> dict[str, Any]:
    """What the timing protocol did (tables measured under it): repeats per run, spread, samples
    rejected and redone, runs accepted under load after the last retry, CPU share, whether the
    table was measured under the protocol at all."""
    timed = df[df["status"] != "skipped"]
    if not measured_under_protocol(df) or timed.empty:
        return {"measured": False}

    def col(name: str) -> np.ndarray:
        return pd_numeric(timed, name)

    runs, spread, share, calls = col("time_runs"), col("spread"), col("cpu_share"), col("calls")
    return {
        "measured": True,
        "runs": int(np.isfinite(runs).sum()),
        "repeats_median": float(np.nanmedian(runs)) if np.isfinite(runs).any() else math.nan,
        "repeats_max": float(np.nanmax(runs)) if np.isfinite(runs).any() else math.nan,
        "calls_max": float(np.nanmax(calls)) if np.isfinite(calls).any() else 1.0,
        "spread_median": float(np.nanmedian(spread)) if np.isfinite(spread).any() else math.nan,
        "rejected": int(np.nansum(col("rejected"))),
        "loaded": int(np.nansum(col("loaded"))),
        "cpu_share_median": float(np.nanmedian(share)) if np.isfinite(share).any() else math.nan,
        "kernel_spread": kernel_spread(timed),
    }


def pd_numeric(df: pd.DataFrame, name: str) -> np.ndarray:
    """A column as floats (booleans as 0/1, missing as NaN)."""
    import pandas as pd

    if name not in df.columns:
        return np.full(len(df), math.nan)
    col = df[name]
    if col.dtype == object:
        col = col.map({True: 1.0, False: 0.0, "True": 1.0, "False": 0.0})
    return pd.to_numeric(col, errors="coerce").to_numpy(dtype=float)


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


def _machine(df: pd.DataFrame) -> dict[str, Any]:
    """Load average at the measurements, wall-clock span of the jobs, their summed time, how many
    ran at once, status counts."""
    load = df[df["status"] != "skipped"]["load1"].to_numpy(dtype=float)
    load = load[np.isfinite(load)]
    jobs = df.drop_duplicates(["N", "config"])
    starts = jobs["job_started"].to_numpy(dtype=float)
    ends = starts + jobs["job_wall_s"].to_numpy(dtype=float)
    return {
        "load": {"min": float(np.min(load)), "median": float(np.median(load)), "max": float(np.max(load))}
        if load.size
        else {},
        "protocol": _protocol(df),
        "span_s": float(np.nanmax(ends) - np.nanmin(starts)) if len(df) else math.nan,
        "job_time_s": float(jobs["job_wall_s"].sum()),
        "concurrent_jobs": concurrent_jobs(starts, ends),
        "counts": df["status"].value_counts().to_dict(),
    }


def findings(
    df: pd.DataFrame,
    table1_norms: Sequence[str],
    paper_l4: Mapping[int, float] | None = None,
    paper_l4_eoc: Mapping[int, float] | None = None,
) -> dict:
    """The numbers ``work_precision.md`` states, computed from the measurement table.

    - ``cells``: per (config, tolerance), how many Table 1 cells (``table1_norms`` × N) print
      differently (5 significant digits) from the exact solution's, the worst relative change
      of a total error, the statuses per N (``answered``: an answer at every N).
    - ``needed``: per QP config, the loosest swept tolerance from which every tighter swept
      tolerance leaves all Table 1 cells unchanged at every N (None: none does).
    - ``cheapest``: per N and config, the fastest run that leaves Table 1's row of that N
      unchanged (its tolerance and time).
    - ``eoc``: per (config, tolerance) with an answer at every N, the ``L⁴`` EOCs of the total
      error, and the largest deviation from the published (``paper_l4_eoc``: N → EOC) and from
      the exact EOCs; ``paper_l4`` (N → published L⁴ error) gives the relative deviation of the
      ``L⁴`` errors themselves.
    - ``exact``: the exact solver's times and errors per N, and the log-log slope of the
      ``L⁴``/``W^{1,4}`` errors against total time (assembly + solve) with the time factor per digit.
    - ``closest_l4``: per N with a published ``L⁴`` cell, the run whose total ``L⁴`` error is
      closest to it (relative deviation), next to the exact solution's deviation.
    - ``peers``: our cascade against the PETSc peers (``_peers``): per N the fastest peer run
      that keeps Table 1's digits with status ``ok``, its time and its ratio to ours; per peer
      the time to those digits per N and the exponent ``p`` of ``time ∝ unknowns^p``.
    - ``fair``: ``_fair_race``: per N our fastest exact configuration against the fastest other
      solver to Table 1's digits, from the same (cascade) warm start and cold against cold.
    - ``protocol``: what the timing protocol did (``_protocol``); ratios and rankings use
      ``RANK_KEY`` (CPU seconds).
    - ``load``/``span_s``/``job_time_s``/``concurrent_jobs``/``counts``: the load average at the
      measurements, the wall-clock span of the measurement jobs, their summed run time, the most
      of them that ran at once, and the status counts.
    """
    Ns = sorted(int(N) for N in df["N"].unique())
    t1 = [n for n in table1_norms if f"total_{n}" in df.columns]
    cells = _cell_changes(df, Ns, t1)
    cheapest = _cheapest(df, Ns, t1)
    paper_rates = [paper_l4_eoc.get(N, math.nan) for N in Ns[1:]] if paper_l4_eoc else None
    return {
        "N": Ns,
        "table1_norms": t1,
        "cells": cells,
        "needed": _needed(cells),
        "cheapest": cheapest,
        "peers": _peers(df, Ns, t1),
        "fair": _fair_race(df, Ns, t1),
        "eoc": _l4_eocs(df, Ns, paper_rates, paper_l4),
        "paper_l4_eoc": paper_rates,
        "exact": _exact_cost(df, Ns),
        "closest_l4": _closest_l4(df, paper_l4),
        **_machine(df),
    }
