"""The stability atlas as one table: one row per (case, solver) with the case's parameters, the
condition estimates and the comparison of a scaling case with its reference case."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence

import numpy as np

COLUMNS = [
    "case",
    "group",
    "N",
    "diagonal",
    "jitter",
    "mesh",
    "problem",
    "corrupt",
    "expected",
    "solver",
    "route",
    "status",
    "as_expected",
    "reason",
    "iterations",
    "factorizations",
    "solve_s",
    "norms_s",
    "total_s",
    "kkt_worst",
    "kkt_threshold",
    "kkt_stationarity",
    "kkt_primal",
    "kkt_dual",
    "kkt_complementarity",
    "nan_inf",
    "fp_warnings",
    "n_active",
    "errors_relative",
    "absolute_norms",
    "{errors}",  # err_<norm> for each norm
    "diff_to_active_set",
    "same_contact_as_active_set",
    "reference",
    "ref_diff_u",
    "ref_same_contact",
    "ref_err_rel_change",
    "cond_A",
    "cond_free",
    "lambda_min_A",
]


def _columns(norms: Sequence[str]) -> list[str]:
    out = []
    for col in COLUMNS:
        out += [f"err_{n}" for n in norms] if col == "{errors}" else [col]
    return out


def _reference_comparison(row: Mapping, case: Mapping, arrays: Mapping, ref_info: Mapping, ref_arrays: Mapping,
                          norms: Sequence[str]) -> dict:
    """A scaling case against its reference: ``u_h/A`` vs ``u_h^ref/A_ref``, contact sets, errors."""
    label = row["solver"]
    u, u_ref = arrays.get(f"u_{label}"), ref_arrays.get(f"u_{label}")
    s = float(case["problem"].get("A", 1.0)) / float(ref_info["case"]["problem"].get("A", 1.0))
    rec: dict = {"reference": ref_info["case"]["name"]}
    if u is None or u_ref is None or not s > 0:
        return rec
    scale = max(np.abs(u_ref).max(initial=0.0), np.finfo(float).tiny)
    rec["ref_diff_u"] = float(np.abs(u / s - u_ref).max(initial=0.0) / scale)
    rec["ref_same_contact"] = bool(np.array_equal(arrays[f"active_{label}"], ref_arrays[f"active_{label}"]))
    ref_row = next(r for r in ref_info["rows"] if r["solver"] == label)
    diffs = [
        abs(row[f"err_{n}"] - ref_row[f"err_{n}"]) / ref_row[f"err_{n}"]
        for n in norms
        if ref_row.get(f"err_{n}") and f"err_{n}" in row
    ]
    rec["ref_err_rel_change"] = max(diffs) if diffs else math.nan
    return rec


def atlas_table(case_infos: Sequence[Mapping], case_arrays: Sequence[Mapping[str, np.ndarray]], norms: Sequence[str]):
    """One row per (case, solver), with the case's parameters, the condition estimates and,
    for cases with a ``reference``, the comparison with the reference case's solution
    scaled by the amplitude ratio (``‖u_h/A - u_h^ref/A_ref‖∞ / ‖u_h^ref/A_ref‖∞``), its
    contact set and its relative errors."""
    import pandas as pd

    by_name = {info["case"]["name"]: (info, arrays) for info, arrays in zip(case_infos, case_arrays, strict=True)}
    records = []
    for info, arrays in zip(case_infos, case_arrays, strict=True):
        case = info["case"]
        ref = case.get("reference")
        ref_info, ref_arrays = by_name.get(ref, (None, None)) if ref else (None, None)
        for row in info["rows"]:
            rec = {
                "case": case["name"],
                "group": case["group"],
                "N": case["N"],
                "diagonal": case["diagonal"],
                "jitter": case["jitter"],
                "mesh": json.dumps(case["mesh"], sort_keys=True) if case.get("mesh") else "",
                "problem": json.dumps(case["problem"], sort_keys=True),
                "corrupt": case["corrupt"] or "",
                "expected": info["expect"],
                **{k: v for k, v in row.items()},
                "cond_A": info["cond"].get("cond_A", math.nan),
                "cond_free": info["cond"].get("cond_free", math.nan),
                "lambda_min_A": info["cond"].get("lambda_min", math.nan),
            }
            if ref_info is not None:
                rec.update(_reference_comparison(row, case, arrays, ref_info, ref_arrays, norms))
            records.append(rec)
    df = pd.DataFrame.from_records(records)
    front = _columns(norms)
    for col in front:
        if col not in df.columns:
            df[col] = math.nan
    return df[front + [c for c in df.columns if c not in front]]
