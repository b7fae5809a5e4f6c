"""Findings of the work-precision study: what ``work_precision.md`` states, in numbers.

Reads the measurement table (``paper_figures/work_precision.csv``, written by
``signorini.work_precision.collect_stage``) and computes: how many Table 1 cells each
(solver, tolerance) changes in their printed 5 significant digits, the tolerance each solver
needs so that none changes, the fastest run per mesh that keeps them, the ``L⁴`` EOCs of the
inexact solutions against the published Table 2 column, the published ``L⁴`` cells each run
comes closest to, and the exact solver's cost per digit.  Kept apart from the measurement
module so that editing the findings re-renders the report without re-running the solves.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from signorini.artifacts import atomic_write_text
from signorini.work_precision import EXACT_LABEL, read_measurements

if TYPE_CHECKING:
    import pandas as pd


def printed(x: float) -> str:
    """A cell of Table 1 as printed (5 significant digits, ``tables.sci_md``)."""
    from signorini.tables import sci_md

    return sci_md(x) if np.isfinite(x) else "—"


def tolerance_order(df: pd.DataFrame) -> list[tuple[str, str]]:
    """(config, tol_label) pairs in plotting order: configs as they appear, the exact solver's
    single run, then each QP solver's default followed by its tolerances loose to tight."""
    out = []
    for config in dict.fromkeys(df["config"]):
        sub = df[df["config"] == config]
        labels = list(dict.fromkeys(sub["tol_label"]))
        rest = sorted((lab for lab in labels if lab not in ("default", EXACT_LABEL)), key=float, reverse=True)
        out += [(config, lab) for lab in labels if lab in ("default", EXACT_LABEL)] + [(config, lab) for lab in rest]
    return out


def _runs(df: pd.DataFrame, config: str, label: str) -> pd.DataFrame:
    """The rows of one (configuration, tolerance) indexed by N."""
    return df[(df["config"] == config) & (df["tol_label"] == label)].set_index("N")


def _unchanged(row: pd.Series, norms: Sequence[str]) -> bool | None:
    """Whether the run's total errors print like the exact ones in every Table 1 column
    (None: the run has no answer)."""
    if not norms or not np.isfinite(float(row[f"total_{norms[0]}"])):
        return None
    return all(printed(float(row[f"total_{n}"])) == printed(float(row[f"disc_{n}"])) for n in norms)


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
    - ``load``/``span``: the load average at the measurements and the wall-clock span of the
      measurement jobs (first start to last end).
    """
    from signorini.convergence import eoc

    Ns = sorted(int(N) for N in df["N"].unique())
    t1 = [n for n in table1_norms if f"total_{n}" in df.columns]
    order = tolerance_order(df)
    cells = []
    for config, label in order:
        sub = _runs(df, config, label)
        changed, worst, answered = 0, 0.0, True
        for N in Ns:
            row = sub.loc[N] if N in sub.index else None
            same = _unchanged(row, t1) if row is not None else None
            if same is None:
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
    cheapest: dict[int, dict[str, dict]] = {}
    for N in Ns:
        cheapest[N] = {}
        for config in dict.fromkeys(df["config"]):
            rows = df[(df["config"] == config) & (df["N"] == N)]
            good = [r for _, r in rows.iterrows() if _unchanged(r, t1)]
            if good:
                fastest = min(good, key=lambda r: float(r["time_s"]))
                cheapest[N][config] = {"tol_label": str(fastest["tol_label"]), "time_s": float(fastest["time_s"])}
    h = np.array([1.0 / N for N in Ns])
    eocs, exact_eoc = [], None
    paper_rates = [paper_l4_eoc.get(N, math.nan) for N in Ns[1:]] if paper_l4_eoc else None
    for config, label in order:
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
    exact: dict[str, Any] = {}
    exact_rows = df[df["tol_label"] == EXACT_LABEL]
    if not exact_rows.empty:
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
    measured = df[df["status"] != "skipped"]
    load = measured["load1"].to_numpy(dtype=float)
    ends = (df["job_started"] + df["job_wall_s"]).to_numpy(dtype=float)
    return {
        "N": Ns,
        "table1_norms": t1,
        "cells": cells,
        "needed": needed,
        "cheapest": cheapest,
        "eoc": eocs,
        "paper_l4_eoc": paper_rates,
        "exact": exact,
        "closest_l4": closest,
        "load": {"min": float(np.min(load)), "median": float(np.median(load)), "max": float(np.max(load))}
        if load.size
        else {},
        "span_s": float(np.nanmax(ends) - np.nanmin(df["job_started"])) if len(df) else math.nan,
        "job_time_s": float(df.drop_duplicates(["N", "config"])["job_wall_s"].sum()),
        "counts": df["status"].value_counts().to_dict(),
    }


def report_stage(
    csv_path: str | os.PathLike,
    paper_table1: str | os.PathLike,
    paper_table2: str | os.PathLike,
    out_md: str | os.PathLike,
    table1_norms: Sequence[str] | None = None,
    source: str = "paper",
) -> dict:
    """``work_precision.md``: the findings (``findings``, against the published Tables 1 and 2
    in ``workflow/reference/``) rendered by ``tables.work_precision_md``."""
    from signorini.tables import TABLE1_NORMS, read_table_csv, work_precision_md

    df = read_measurements(csv_path)
    p1, p2 = read_table_csv(paper_table1), read_table_csv(paper_table2)

    def by_N(table: Mapping[str, Mapping[str, float]]) -> dict[int, float]:
        return {int(k.split("/")[1]): v["L4"] for k, v in table.items() if k.startswith("1/") and "L4" in v}

    found = findings(df, table1_norms or TABLE1_NORMS, by_N(p1), by_N(p2))
    atomic_write_text(out_md, work_precision_md(df, found, source))
    return found
