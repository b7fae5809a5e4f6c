"""``work_precision.md`` (``signorini.studies.work_precision.report``): the setup, which tolerance
keeps Table 1, the run time to its digits and the failures, from a measurement table."""

from __future__ import annotations

from signorini.studies.work_precision.findings import findings
from signorini.studies.work_precision.report import work_precision_md


def _table(md: str, heading: str) -> list[list[str]]:
    """The rows of the Markdown table under ``heading`` (cells stripped)."""
    section = md.split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("|")]
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows[2:]]


def test_the_report_names_the_tolerance_that_keeps_table_1_and_every_failure(measurements):
    md = work_precision_md(measurements, findings(measurements, ["L4", "W14"]))
    assert "AS, QP, SCS" in md and "1e-02, 1e-06" in md  # the setup: solvers and tolerances swept
    digits = {(r[0], r[1]): r for r in _table(md, "Which tolerance keeps Table 1")}
    assert digits[("QP", "1e-02")][2] == "3/6" and digits[("QP", "1e-06")][2] == "0/6"
    assert digits[("AS", "exact")][2] == "0/6" and digits[("SCS", "1e-06")][2] == "0/6 (partial)"
    assert digits[("SCS", "1e-06")][4] == "failed failed failed"
    time_rows = {r[0]: r[1:] for r in _table(md, "Run time to Table 1's digits")}
    assert time_rows["SCS"] == ["—", "—", "—"] and all(cell.endswith("(1e-06)") for cell in time_rows["QP"])
    assert _table(md, "Failures, inaccurate answers and skips") == [
        ["SCS", "failed", "1e-06 at N = 10, 20, 40", "solver status infeasible"]
    ]
