"""The one selection rule (``signorini.studies.work_precision.selection``): a run keeps Table 1's
digits only with status ok; a configuration's tolerance is the loosest swept one at which every
mesh keeps them, fixed across the meshes."""

from __future__ import annotations

import math

import pandas as pd

from signorini.studies.work_precision.selection import (
    digits_unchanged,
    keeps_digits,
    printed,
    selected_runs,
    selected_tolerances,
    swept,
)

NORMS = ["L4", "W14"]


def _perturb(df: pd.DataFrame, config: str, tol: str, N: int, **values) -> pd.DataFrame:
    df = df.copy()
    where = (df["config"] == config) & (df["tol_label"] == tol) & (df["N"] == N)
    for name, value in values.items():
        df.loc[where, name] = value
    return df


def test_a_run_keeps_table_1s_digits_only_with_status_ok_and_every_cell_printed_alike(measurements):
    row = measurements[(measurements["config"] == "qp") & (measurements["tol_label"] == "1e-06")].iloc[0]
    assert digits_unchanged(row, NORMS) and keeps_digits(row, NORMS)
    assert not keeps_digits({**row, "status": "inaccurate"}, NORMS)  # the same digits, an uncertified answer
    changed = measurements[(measurements["config"] == "qp") & (measurements["tol_label"] == "1e-02")].iloc[0]
    assert digits_unchanged(changed, NORMS) is False and not keeps_digits(changed, NORMS)
    failed = measurements[measurements["config"] == "scs"].iloc[0]
    assert digits_unchanged(failed, NORMS) is None and not keeps_digits(failed, NORMS)
    assert printed(0.1 / 40**2) == "6.2500·10⁻⁵" and printed(math.nan) == "—"


def test_the_swept_tolerances_loosest_first_without_the_default():
    assert swept(["default", "1e-08", "1e-02", "1e-04"]) == ["1e-02", "1e-04", "1e-08"]
    assert swept(["exact"]) == ["exact"]


def test_the_selected_tolerance_is_the_loosest_that_keeps_the_digits_on_every_mesh(measurements):
    assert selected_tolerances(measurements, NORMS) == {"exact": "exact", "qp": "1e-06", "scs": None}
    chosen = selected_runs(measurements, NORMS)
    assert sorted(zip(chosen["config"], chosen["tol_label"], chosen["N"], strict=True)) == [
        ("exact", "exact", 10),
        ("exact", "exact", 20),
        ("exact", "exact", 40),
        ("qp", "1e-06", 10),
        ("qp", "1e-06", 20),
        ("qp", "1e-06", 40),
    ]


def test_an_inaccurate_run_on_one_mesh_moves_the_tolerance_to_a_tighter_one_or_none(measurements, run_row):
    """An inaccurate answer at 1e-06 on one mesh: the solver is not given 1e-06, not even on the
    other meshes; with a tighter tolerance that keeps the digits everywhere it gets that one."""
    inaccurate = _perturb(measurements, "qp", "1e-06", 20, status="inaccurate")
    assert selected_tolerances(inaccurate, NORMS)["qp"] is None
    tighter = pd.concat([inaccurate, pd.DataFrame([run_row(N, "qp", "1e-08", [0.5]) for N in (10, 20, 40)])])
    assert selected_tolerances(tighter, NORMS)["qp"] == "1e-08"


def test_digits_changed_on_one_mesh_or_a_missing_mesh_withhold_the_tolerance(measurements):
    changed = _perturb(measurements, "qp", "1e-06", 40, total_L4=0.1 / 40**2 * (1 + 1e-3))
    assert selected_tolerances(changed, NORMS)["qp"] is None
    missing = measurements[~((measurements["config"] == "qp") & (measurements["N"] == 10))]
    assert selected_tolerances(missing, NORMS)["qp"] is None
    exact_off = _perturb(measurements, "exact", "exact", 10, status="inaccurate")
    assert selected_tolerances(exact_off, NORMS)["exact"] is None  # the exact configurations obey the same rule


def test_the_default_tolerance_is_never_selected(measurements, run_row):
    default = pd.DataFrame([run_row(N, "qp", "default", [0.01]) for N in (10, 20, 40)])
    only_default = pd.concat([measurements[measurements["tol_label"] != "1e-06"], default])
    assert selected_tolerances(only_default, NORMS)["qp"] is None
