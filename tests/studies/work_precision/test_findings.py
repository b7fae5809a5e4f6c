"""The findings of the work-precision study (``signorini.studies.work_precision.findings``): the
selected runs in every comparison, the fastest and the comparisons from the same start with their
intervals, the exponents, what the timing protocol did, what the table records of the machine."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import ROOT

from signorini.studies.work_precision.findings import findings
from signorini.studies.work_precision.table import Run
from signorini.timing import Protocol

NORMS = ["L4", "W14"]


def test_findings_select_one_tolerance_per_configuration_and_time_its_runs(measurements):
    found = findings(measurements, NORMS, paper_l4={10: 1e-3}, paper_l4_eoc={20: 2.0, 40: 2.1})
    assert found["tolerance"] == {"exact": "exact", "qp": "1e-06", "scs": None}
    assert found["needed"] == {"qp": "1e-06", "scs": None}
    at40 = found["selected"][40]
    assert set(at40) == {"exact", "qp"} and at40["qp"]["tol_label"] == "1e-06"
    assert at40["qp"]["value"] == pytest.approx(0.12) and at40["qp"]["samples"] == 3
    assert at40["qp"]["lo"] == pytest.approx(0.12 * 0.98) and at40["qp"]["hi"] == pytest.approx(0.12 * 1.02)
    cells = {(c["config"], c["tol_label"]): c for c in found["cells"]}
    assert cells[("qp", "1e-02")]["changed"] == 3 and cells[("qp", "1e-06")]["changed"] == 0
    assert cells[("qp", "1e-06")]["selected"] and cells[("qp", "1e-06")]["keeping"] == 3
    assert cells[("qp", "1e-02")]["keeping"] == 0 and not cells[("scs", "1e-06")]["selected"]
    exact_eoc = next(e for e in found["eoc"] if e["tol_label"] == "exact")
    np.testing.assert_allclose(exact_eoc["eoc"], [2.0, 2.0])
    assert exact_eoc["max_dev_paper"] == pytest.approx(0.1)
    # time ∝ N ≈ unknowns^(1/2); the exact solver's errors against assembly + solve (0.011 N s)
    assert found["scaling"]["qp"]["value"] == pytest.approx(0.5, abs=0.05)
    assert found["exact"]["slope_L4"]["value"] == pytest.approx(-2.0, rel=1e-3)
    assert found["exact"]["time_factor_per_digit_L4"]["value"] == pytest.approx(10**0.5, rel=1e-3)


def test_an_inaccurate_run_is_selected_nowhere(measurements, changed):
    """With the QP solver's 1e-06 run inaccurate on the finest mesh it has no selected tolerance: it
    is neither ranked there nor on the coarser meshes, where its runs are ok."""
    runs = changed(measurements, {"config": "qp", "tol_label": "1e-06", "N": 40}, status="inaccurate")
    found = findings(runs, NORMS)
    assert found["tolerance"]["qp"] is None
    assert all("qp" not in found["selected"][N] for N in (10, 20, 40))
    assert [r["config"] for r in found["fastest"]] == ["exact"] and "qp" not in found["scaling"]


def _race(run_row, samples_around, warm_other: float, width: float = 0.02) -> list[Run]:
    """Ours from the cascade and cold, a peer from the cascade start and cold, on N = 101, 201."""
    rows = []
    for N in (101, 201):
        rows += [
            run_row(N, "ours", "exact", samples_around(1.0), start="cascade"),
            run_row(N, "ours_cold", "exact", samples_around(4.0), start="cold"),
            run_row(N, "mg_cold", "exact", samples_around(5.0 if N == 101 else 1.5), start="cold", solver="multigrid"),
            run_row(N, "tron", "1e-08", samples_around(3.0), solver="petsc_tao"),
            run_row(
                N, "tron_ws", "1e-08", samples_around(warm_other, width=width), start="cascade", solver="petsc_tao"
            ),
        ]
    return rows


def test_same_warm_start_and_cold_against_cold_with_their_intervals(run_row, samples_around):
    found = findings(_race(run_row, samples_around, 2.0), ["L4"])
    warm, cold = found["fair"]["same_warm_start"], found["fair"]["cold_against_cold"]
    assert [(r["N"], r["ours"]["config"], r["other"]["config"], r["ratio"]["verdict"]) for r in warm] == [
        (101, "ours", "tron_ws", "above"),
        (201, "ours", "tron_ws", "above"),
    ]
    assert warm[0]["ratio"]["value"] == pytest.approx(2.0)
    assert warm[0]["ratio"]["lo"] == pytest.approx(1.96 / 1.02) and warm[0]["ratio"]["hi"] == pytest.approx(2.04 / 0.98)
    # per mesh our fastest exact configuration of that start
    assert [(r["ours"]["config"], r["ratio"]["value"], r["ratio"]["verdict"]) for r in cold] == [
        ("ours_cold", pytest.approx(0.75), "below"),
        ("mg_cold", pytest.approx(2.0), "above"),
    ]


def test_a_ratio_whose_interval_straddles_1_is_a_tie(run_row, samples_around):
    """The peer from the cascade start 5 % slower than ours, its samples ±10 %: a tie."""
    found = findings(_race(run_row, samples_around, 1.05, width=0.1), ["L4"])
    warm = found["fair"]["same_warm_start"]
    assert [r["ratio"]["verdict"] for r in warm] == ["tie", "tie"]
    assert warm[0]["ratio"]["lo"] < 1.0 < warm[0]["ratio"]["hi"]
    fastest = found["fastest"]
    assert fastest[0]["config"] == "ours" and fastest[1]["config"] == "tron_ws"
    assert fastest[1]["vs_fastest"]["verdict"] == "tie" and fastest[0]["vs_fastest"] is None


def test_the_protocol_counts_what_happened(measurements, changed):
    """From the table: the stops, the samples per run with an answer, the median spreads overall and
    of the runs short enough for the budget to hold ``min_repeats`` samples."""
    p = findings(measurements, NORMS, protocol=Protocol(budget_s=0.15, min_repeats=3))["protocol"]
    assert p["timed"] == 12 and p["raised"] == 0
    assert p["stops"] == {"spread": 3, "budget": 3, "max_repeats": 3, "answer rejected": 3}
    assert p["answered"] == 9 and p["samples"] == {3: 9} and p["several"] == 9
    assert p["spread_median"] == pytest.approx(0.04, rel=1e-3)
    assert p["short_s"] == pytest.approx(0.05) and p["short"] == 6  # 0.01 … 0.04 s of 0.01 … 0.12 s
    assert p["spread_median_short"] == pytest.approx(0.04, rel=1e-3)
    fewer = changed(measurements, {"config": "qp"}, times="0.05", spread=0.0)
    q = findings(fewer, NORMS, protocol=Protocol(budget_s=0.15))["protocol"]
    assert q["samples"] == {1: 6, 3: 3} and q["several"] == 3


def test_the_table_says_what_it_records_of_the_machine_and_the_software(measurements, changed):
    found = findings(measurements, NORMS)
    assert found["software"] == {"petsc": [], "machines": [], "unrecorded": 12}
    record = {"cores": 2, "cpu_model": "AMD EPYC", "hypervisor": True}
    runs = changed(measurements, {}, machine=json.dumps(record), peer_info="PETSc 3.18.5: tron")
    runs = changed(runs, {"N": 10}, machine="")  # measured before the column
    sw = findings(runs, NORMS)["software"]
    assert sw == {"petsc": ["PETSc 3.18.5"], "machines": [{"record": record, "runs": 8}], "unrecorded": 4}


def test_on_the_committed_table_every_section_uses_the_same_selected_runs():
    """BNLS at 1e-06 is inaccurate at N = 501 (and 401): its tolerance is 1e-08 on every mesh; TRON +
    BoomerAMG from the cascade start has one time at N = 401 in every section."""
    from signorini.studies.work_precision.table import read_runs

    runs = read_runs(ROOT / "paper_figures/work_precision.csv")
    keep = ["active_set", "multigrid", "petsc_bnls", "petsc_bnls_ws", "petsc_tron_boomeramg_ws", "osqp"]
    found = findings([r for r in runs if r.config in keep], ["L4", "Linf", "W14", "W1inf", "H12"])
    assert found["tolerance"]["petsc_bnls"] == "1e-08" and found["tolerance"]["osqp"] is None
    assert {r["tol_label"] for N in found["N"] for c, r in found["selected"][N].items() if c == "petsc_bnls"} == {
        "1e-08"
    }
    tron = found["selected"][401]["petsc_tron_boomeramg_ws"]
    warm = next(r for r in found["fair"]["same_warm_start"] if r["N"] == 401)
    assert warm["other"]["config"] == "petsc_tron_boomeramg_ws" and warm["other"]["value"] == tron["value"]
    assert all(math.isfinite(found["scaling"][c]["value"]) for c in found["scaling"])


def test_the_peers_are_the_runs_of_that_kind_with_petscs_reasons(measurements, changed):
    assert findings(measurements, NORMS)["peers"] == {}
    peers = changed(measurements, {"config": "qp"}, solver="petsc_tao", converged_reason="CONVERGED_GATOL")
    assert findings(peers, NORMS)["peers"] == {
        "qp": {"label": "QP", "statuses": {"ok": 6}, "reasons": ["CONVERGED_GATOL"]}
    }


def test_calls_rejections_and_loaded_runs_are_counted_where_recorded(measurements, changed):
    """A flag or a count a run did not record (None) counts as nothing."""
    runs = changed(measurements, {"config": "qp", "tol_label": "1e-02"}, loaded=True, rejected=2, calls=5)
    runs = changed(runs, {"config": "scs"}, loaded=None, rejected=None, calls=None)
    p = findings(runs, NORMS)["protocol"]
    assert (p["loaded"], p["rejected"], p["calls_max"]) == (3, 6, 5.0)


def test_concurrent_jobs_counts_the_largest_overlap_of_job_intervals():
    """Back-to-back jobs (one ends as the next starts) never ran together; nested ones did."""
    from signorini.studies.work_precision.findings import concurrent_jobs

    one_core = np.array([0.0, 10.0, 25.0]), np.array([10.0, 25.0, 30.0])
    assert concurrent_jobs(*one_core) == 1
    # [0, 11) and [1, 12) overlap, as do [12, 20) and [13, 14); a NaN (a skipped job) is left out
    two_cores = np.array([0.0, 1.0, 12.0, 13.0, np.nan]), np.array([11.0, 12.0, 20.0, 14.0, np.nan])
    assert concurrent_jobs(*two_cores) == 2
    assert concurrent_jobs(np.array([0.0, 1.0, 2.0]), np.array([9.0, 9.0, 9.0])) == 3


def test_kernel_spread_is_the_largest_range_of_the_job_medians_of_one_mesh():
    from signorini.studies.work_precision.findings import kernel_spread

    rows = [  # N, config, ref_s per run: job medians 1.0 and 1.1 at N = 11, 2.0 and 2.0 at N = 21
        (11, "a", 1.0),
        (11, "a", 1.0),
        (11, "a", 5.0),
        (11, "b", 1.1),
        (21, "a", 2.0),
        (21, "b", 2.0),
        (21, "c", np.nan),
    ]
    runs = [Run(N, 1 / N, (N + 1) ** 2, config, "active_set", config, ref_s=ref) for N, config, ref in rows]
    assert kernel_spread(runs) == pytest.approx(0.1 / 1.05)
    assert math.isnan(kernel_spread(runs[4:5]))
