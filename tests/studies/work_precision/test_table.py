"""Stage ``work_precision_table`` (``signorini.studies.work_precision.table``): every measurement
record in one table, read back, and the plotting order of the tolerances."""

from __future__ import annotations

import math

import pandas as pd

from signorini.pipeline.artifacts import save_json
from signorini.studies.work_precision.table import ID_COLUMNS, read_measurements, table_stage, tolerance_order


def _record(N: int, config: str, tol_label: str, **extra) -> dict:
    return {
        "N": N,
        "config": config,
        "label": config,
        "tol_label": tol_label,
        "status": "ok",
        "time_s": 0.1,
        "disc_L4": 1e-3 / N,
        "total_L4": 1e-3 / N,
        "alg_L4": 0.0,
        "disc_W14": 1e-2,
        "total_W14": 1e-2,
        "alg_W14": 0.0,
        **extra,
    }


def test_the_records_of_every_job_in_one_table_sorted_by_mesh_and_configuration(tmp_path):
    jobs = {
        "N21_qp.json": [_record(21, "qp", "default"), _record(21, "qp", "1e-08"), _record(21, "qp", "1e-02")],
        "N11_exact.json": [_record(11, "exact", "exact")],
        "N11_qp.json": [_record(11, "qp", "1e-02", status="failed", reason="time limit (30 s)")],
    }
    for name, records in jobs.items():
        save_json(tmp_path / name, {"records": records})
    out = tmp_path / "work_precision.csv"
    df = table_stage([tmp_path / name for name in jobs], out)
    norms = [f"{kind}_{n}" for kind in ("alg", "total", "disc") for n in ("L4", "W14")]
    assert list(df.columns) == ID_COLUMNS + norms
    assert list(zip(df["N"], df["config"], strict=True)) == [
        (11, "exact"),
        (11, "qp"),
        (21, "qp"),
        (21, "qp"),
        (21, "qp"),
    ]
    assert math.isnan(df["time_ref"].iloc[0])  # a column no record has
    back = read_measurements(out)
    assert list(back["reason"]) == ["", "time limit (30 s)", "", "", ""]
    assert list(back["machine"]) == [""] * 5  # recorded by no record here: read as empty
    pd.testing.assert_series_equal(back["total_L4"], df["total_L4"])
    # the exact solver's run, then each QP solver's default and its tolerances loose to tight
    assert tolerance_order(back) == [("exact", "exact"), ("qp", "default"), ("qp", "1e-02"), ("qp", "1e-08")]
