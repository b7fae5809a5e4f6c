"""Stage ``work_precision_table`` (``signorini.studies.work_precision.table``): every measurement
record in one table, one ``Run`` per row, read back and written again byte for byte, the kind of
each run, and the plotting order of the tolerances."""

from __future__ import annotations

import csv
import math

from helpers import ROOT

from signorini.pipeline.artifacts import save_json
from signorini.studies.work_precision.routes import Kind
from signorini.studies.work_precision.table import ID_COLUMNS, Run, read_runs, sweeps, table_stage, write_runs


def _record(N: int, config: str, tol_label: str, **extra) -> dict:
    return {
        "N": N,
        "h": 1 / N,
        "n_dofs": (N + 1) ** 2,
        "config": config,
        "solver": "active_set" if tol_label == "exact" else "OSQP",
        "label": config,
        "tol_label": tol_label,
        "status": "ok",
        "time_s": 0.1,
        "time_runs": 1,
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
        "N11_exact.json": [_record(11, "exact", "exact", calls=3, loaded=False)],
        "N11_qp.json": [_record(11, "qp", "1e-02", status="failed", reason="time limit (30 s)", peer={"x": 1})],
    }
    for name, records in jobs.items():
        save_json(tmp_path / name, {"records": records})
    out = tmp_path / "work_precision.csv"
    runs = table_stage([tmp_path / name for name in jobs], out)
    with open(out, encoding="utf-8", newline="") as f:
        header, *rows = list(csv.reader(f))
    norms = [f"{kind}_{n}" for kind in ("alg", "total", "disc") for n in ("L4", "W14")]
    assert header == ID_COLUMNS + norms and len(ID_COLUMNS) == 43
    assert [(r.N, r.config) for r in runs] == [(11, "exact"), (11, "qp"), (21, "qp"), (21, "qp"), (21, "qp")]
    assert math.isnan(runs[0].time_ref) and runs[1].calls is None  # recorded by no run, by this one not
    assert [row[ID_COLUMNS.index("calls")] for row in rows] == ["3.0", "", "", "", ""]  # a count beside gaps
    assert [row[ID_COLUMNS.index("time_runs")] for row in rows] == ["1"] * 5
    back = read_runs(out)
    assert [r.reason for r in back] == ["", "time limit (30 s)", "", "", ""]
    assert [r.machine for r in back] == [""] * 5  # recorded by no record here: read as empty
    assert [r.total["L4"] for r in back] == [r.total["L4"] for r in runs]
    assert back[0].calls == 3 and back[0].loaded is False and back[1].loaded is None
    write_runs(back, tmp_path / "again.csv")
    assert (tmp_path / "again.csv").read_bytes() == out.read_bytes()
    # the exact solver's run, then each QP solver's default and its tolerances loose to tight
    assert list(sweeps(back)) == [("exact", "exact"), ("qp", "default"), ("qp", "1e-02"), ("qp", "1e-08")]


def _rows(path) -> list[list[str]]:
    with open(path, encoding="utf-8", newline="") as f:
        return list(csv.reader(f))


def test_the_committed_table_is_read_and_written_again_unchanged(tmp_path):
    """Every value of ``work_precision.csv`` survives the record type, the ``machine`` column
    included; a table measured before that column is written with it, empty."""
    committed = ROOT / "paper_figures/work_precision.csv"
    write_runs(read_runs(committed), tmp_path / "again.csv")
    before = _rows(committed)
    assert _rows(tmp_path / "again.csv") == before
    machine = before[0].index("machine")
    assert any(row[machine] for row in before[1:])  # the committed study records its machine
    older = [row[:machine] + row[machine + 1 :] for row in before]
    with open(tmp_path / "older.csv", "w", encoding="utf-8", newline="") as f:
        csv.writer(f).writerows(older)
    write_runs(read_runs(tmp_path / "older.csv"), tmp_path / "older_again.csv")
    after = _rows(tmp_path / "older_again.csv")
    assert {row[machine] for row in after[1:]} == {""}
    assert [row[:machine] + row[machine + 1 :] for row in after] == older


def test_every_run_knows_its_kind():
    def run(solver: str) -> Run:
        return Run(101, 0.01, 10404, "c", solver, "c")

    assert [run(s).kind for s in ("active_set", "multigrid", "OSQP", "CLARABEL", "petsc_tao", "petsc_snes")] == [
        Kind.EXACT,
        Kind.EXACT,
        Kind.QP,
        Kind.QP,
        Kind.PEER,
        Kind.PEER,
    ]
