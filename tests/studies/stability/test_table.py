"""The atlas as one table (``signorini.studies.stability.table``): one row per case and solver, a
scaling case against its reference."""

from __future__ import annotations

import json

from signorini.studies.stability.table import atlas_table


def test_one_row_per_case_and_solver_with_the_reference_comparison(small_atlas):
    infos, arrays, norms = small_atlas
    df = atlas_table(infos, arrays, norms)
    assert list(df["case"]) == ["A_10", "A_1e-6", "bad_spd"] and set(df["solver"]) == {"active_set"}
    assert list(df.columns[:14]) == ["case", "group", "N", "diagonal", "jitter", "mesh", "problem", "corrupt",
                                     "expected", "solver", "route", "status", "as_expected", "reason"]
    assert set(df["mesh"]) == {""}  # the Friedrichs–Keller mesh of N and the diagonal
    assert {"err_L4", "err_H12"} <= set(df.columns) and json.loads(df["problem"].iloc[1])["A"] == 1e-6
    scaled = df.set_index("case").loc["A_1e-6"]
    assert scaled["reference"] == "A_10" and scaled["ref_diff_u"] <= 1e-10 and scaled["ref_same_contact"]
    assert scaled["ref_err_rel_change"] <= 1e-8  # relative errors do not depend on the amplitude
    bad = df.set_index("case").loc["bad_spd"]
    assert bad["status"] == "failed" and bad["as_expected"] and bad["expected"] == "error"
    assert bad["reason"].startswith("BadInputError") and bad["corrupt"] == "non_spd"
