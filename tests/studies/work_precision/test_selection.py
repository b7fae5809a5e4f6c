"""The one selection rule (``signorini.studies.work_precision.selection``): a run keeps Table 1's
digits only with status ok; a configuration's tolerance is the loosest swept one at which every
mesh keeps them, fixed across the meshes."""

from __future__ import annotations

import dataclasses
import math

from signorini.studies.work_precision.selection import (
    digits_unchanged,
    keeps_digits,
    printed,
    selected_runs,
    selected_tolerances,
    swept,
)

NORMS = ["L4", "W14"]


def _first(runs, config: str, tol: str | None = None):
    return next(r for r in runs if r.config == config and tol in (None, r.tol_label))


def test_a_run_keeps_table_1s_digits_only_with_status_ok_and_every_cell_printed_alike(measurements):
    row = _first(measurements, "qp", "1e-06")
    assert digits_unchanged(row, NORMS) and keeps_digits(row, NORMS)
    assert not keeps_digits(dataclasses.replace(row, status="inaccurate"), NORMS)  # an uncertified answer
    changed = _first(measurements, "qp", "1e-02")
    assert digits_unchanged(changed, NORMS) is False and not keeps_digits(changed, NORMS)
    failed = _first(measurements, "scs")
    assert digits_unchanged(failed, NORMS) is None and not keeps_digits(failed, NORMS)
    assert printed(0.1 / 40**2) == "6.2500·10⁻⁵" and printed(math.nan) == "—"


def test_the_swept_tolerances_loosest_first_without_the_default():
    assert swept(["default", "1e-08", "1e-02", "1e-04"]) == ["1e-02", "1e-04", "1e-08"]
    assert swept(["exact"]) == ["exact"]


def test_the_selected_tolerance_is_the_loosest_that_keeps_the_digits_on_every_mesh(measurements):
    assert selected_tolerances(measurements, NORMS) == {"exact": "exact", "qp": "1e-06", "scs": None}
    chosen = selected_runs(measurements, NORMS)
    assert sorted((r.config, r.tol_label, r.N) for r in chosen) == [
        ("exact", "exact", 10),
        ("exact", "exact", 20),
        ("exact", "exact", 40),
        ("qp", "1e-06", 10),
        ("qp", "1e-06", 20),
        ("qp", "1e-06", 40),
    ]


def test_an_inaccurate_run_on_one_mesh_moves_the_tolerance_to_a_tighter_one_or_none(measurements, run_row, changed):
    """An inaccurate answer at 1e-06 on one mesh: the solver is not given 1e-06, not even on the
    other meshes; with a tighter tolerance that keeps the digits everywhere it gets that one."""
    inaccurate = changed(measurements, {"config": "qp", "tol_label": "1e-06", "N": 20}, status="inaccurate")
    assert selected_tolerances(inaccurate, NORMS)["qp"] is None
    tighter = inaccurate + [run_row(N, "qp", "1e-08", [0.5]) for N in (10, 20, 40)]
    assert selected_tolerances(tighter, NORMS)["qp"] == "1e-08"


def test_digits_changed_on_one_mesh_or_a_missing_mesh_withhold_the_tolerance(measurements, changed):
    total = {"L4": 0.1 / 40**2 * (1 + 1e-3), "W14": 0.2 / 40}
    off = changed(measurements, {"config": "qp", "tol_label": "1e-06", "N": 40}, total=total)
    assert selected_tolerances(off, NORMS)["qp"] is None
    missing = [r for r in measurements if not (r.config == "qp" and r.N == 10)]
    assert selected_tolerances(missing, NORMS)["qp"] is None
    exact_off = changed(measurements, {"config": "exact", "N": 10}, status="inaccurate")
    assert selected_tolerances(exact_off, NORMS)["exact"] is None  # the exact configurations obey the same rule


def test_the_default_tolerance_is_never_selected(measurements, run_row):
    default = [run_row(N, "qp", "default", [0.01]) for N in (10, 20, 40)]
    only_default = [r for r in measurements if r.tol_label != "1e-06"] + default
    assert selected_tolerances(only_default, NORMS)["qp"] is None
