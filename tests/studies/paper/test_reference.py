"""The published tables (``signorini.studies.paper.reference``): reading a table CSV, a column by
mesh, and the relative deviation of ours from the paper's."""

from __future__ import annotations

import math

import pytest
from helpers import ROOT

from signorini.pipeline.paths import REFERENCES
from signorini.studies.paper.reference import by_mesh, read_table_csv, relative_deviation


def test_a_table_csv_skips_comments_and_empty_cells(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("# transcribed\nh, L4, W14\n1/101, 1.0e-3, 2.0e-2\n# a remark\n1/201, 2.5e-4,\nregr., 2.0, 1.0\n")
    table = read_table_csv(path)
    assert table == {"1/101": {"L4": 1e-3, "W14": 2e-2}, "1/201": {"L4": 2.5e-4}, "regr.": {"L4": 2.0, "W14": 1.0}}
    assert by_mesh(table, "W14") == {101: 2e-2} and by_mesh(table, "L4") == {101: 1e-3, 201: 2.5e-4}
    assert relative_deviation(1.1, -1.0) == pytest.approx(2.1) and math.isnan(relative_deviation(1.0, 0.0))


def test_the_transcribed_table_1_has_the_papers_meshes_and_decreasing_errors():
    table = read_table_csv(ROOT / REFERENCES["paper_table1"])
    l4 = by_mesh(table, "L4")
    assert sorted(l4) == [101, 201, 301, 401, 501]
    values = [l4[N] for N in sorted(l4)]
    assert all(a > b > 0 for a, b in zip(values, values[1:], strict=False))
