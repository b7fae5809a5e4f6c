"""A synthetic measurement table (``work_precision.csv``) for the tests of the findings, the report
and the figures: the exact solver, a QP solver at two tolerances and one that fails, on N = 10, 20,
40 with discretisation errors L⁴ ∝ h² and W^{1,4} ∝ h."""

from __future__ import annotations

import math

import pandas as pd
import pytest


@pytest.fixture
def measurements() -> pd.DataFrame:
    rows = []
    for N in (10, 20, 40):
        disc = {"L4": 0.1 / N**2, "W14": 0.2 / N}
        base = {"N": N, "h": 1 / N, "n_dofs": (N + 1) ** 2, "build_s": 0.01 * N, "job_wall_s": 1.0,
                "job_started": 0.0, "load1": 1.0, "reason": "", **{f"disc_{n}": e for n, e in disc.items()}}
        runs = [  # config, label, solver, tolerance, status, time, relative change of the L⁴ error
            ("exact", "AS", "active_set", "exact", "ok", 0.001 * N, 0.0),
            ("qp", "QP", "OSQP", "1e-02", "ok", 0.002 * N, 1e-2),
            ("qp", "QP", "OSQP", "1e-06", "ok", 0.003 * N, 1e-7),
            ("scs", "SCS", "SCS", "1e-06", "failed", 0.004 * N, math.nan),
        ]
        for config, label, solver, tol, status, time_s, rel in runs:
            l4 = disc["L4"] * (1 + rel)
            rows.append({
                **base, "config": config, "label": label, "solver": solver, "tol_label": tol, "status": status,
                "time_s": time_s, "total_L4": l4, "alg_L4": l4 - disc["L4"],
                "total_W14": disc["W14"] if status == "ok" else math.nan, "alg_W14": 0.0,
                "reason": "" if status == "ok" else "solver status infeasible",
            })
    return pd.DataFrame(rows)
