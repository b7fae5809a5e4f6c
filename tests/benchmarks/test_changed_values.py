"""benchmarks/changed_values.py: the changes of rebuilt norm artifacts against their stated uncertainty."""

from __future__ import annotations

import json
from pathlib import Path

from helpers import benchmark

changed_values = benchmark("changed_values")


def _artifact(path: Path, value: float, uncertainty: float | None = None) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {"value": value} | ({"algebraic_error": {"uncertainty": uncertainty}} if uncertainty else {})
    path.write_text(json.dumps(record), encoding="utf-8")


def test_changes_are_measured_in_units_of_the_stated_uncertainty(tmp_path):
    norms = tmp_path / "results/s/N11/norms"
    _artifact(norms / "L4.json.stale", 1.0)
    _artifact(norms / "L4.json", 1.0 + 3e-12, uncertainty=1e-12)
    _artifact(norms / "H12.json.stale", 2.0)
    _artifact(norms / "H12.json", 2.0, uncertainty=1e-12)
    _artifact(norms / "W14.json", 5.0, uncertainty=1e-12)  # rebuilt from nothing: not compared
    rows = changed_values.changes(tmp_path / "results")
    assert [row["artifact"] for row in rows] == ["results/s/N11/norms/L4.json", "results/s/N11/norms/H12.json"]
    assert abs(rows[0]["change_over_uncertainty"] - 3.0) < 1e-3 and rows[1]["change"] == 0.0
    assert changed_values.summary(rows)["s"] == {
        "compared": 2,
        "changed": 1,
        "max_ratio": rows[0]["change_over_uncertainty"],
        "max_relative_change": rows[0]["relative_change"],
    }
