"""Why runs of the atlas fail (``signorini.studies.stability.findings``): each failure class's
paragraph is selected by its condition, checked on the committed ``paper_figures/stability.csv``
and on a copy with one row changed so that the condition no longer holds."""

from __future__ import annotations

import dataclasses

import pandas as pd
import pytest
from helpers import ROOT

from signorini.pipeline.config import load_config
from signorini.studies.stability import findings
from signorini.studies.stability.atlas import parse_atlas


@pytest.fixture(scope="module")
def atlas() -> pd.DataFrame:
    """The committed atlas table, as a user reads it back."""
    return pd.read_csv(ROOT / "paper_figures/stability.csv", encoding="utf-8")


@pytest.fixture(scope="module")
def specs() -> dict:
    """The atlas's solver columns (their limits and tolerances) from the shipped config."""
    return parse_atlas(load_config(ROOT / "workflow/config.yaml")["scenes"]["stability"]).solvers


def changed(df: pd.DataFrame, case: str, solver: str, **values) -> pd.DataFrame:
    """A copy of ``df`` with the run ``case/solver`` given ``values``."""
    out = df.copy()
    row = (out["case"] == case) & (out["solver"] == solver)
    assert row.sum() == 1, f"{case}/{solver} is not one run of the table"
    for column, value in values.items():
        out.loc[row, column] = value
    return out


def value(df: pd.DataFrame, case: str, solver: str, column: str):
    """The run ``case/solver``'s ``column``: the figures the paragraphs quote, read from the table
    (a regenerated atlas moves its timings and round-off)."""
    row = (df["case"] == case) & (df["solver"] == solver)
    assert row.sum() == 1, f"{case}/{solver} is not one run of the table"
    return df.loc[row, column].iloc[0]


def test_interior_point_failures_are_explained_where_every_node_is_biactive(atlas, specs):
    text = findings.degenerate_complementarity(atlas, specs)
    assert text.startswith("*Degenerate complementarity* (f_zero/clarabel, f_zero/clarabel_raw, f_zero_c0/clarabel, "
                           "f_zero_c0/clarabel_raw).")
    assert "164/164 in f_zero, 164/164 in f_zero_c0" in text and "With c = 0 as well (f_zero_c0)" in text
    assert "f_zero/clarabel complementarity 9.5e-01, stationarity 1.1e-05, 0 nodes in contact" in text
    assert "Strength: by construction" in text
    # the exact solver leaves one node of f_zero free: not every node biactive there
    one_free = changed(atlas, "f_zero", "active_set", n_active=163)
    text = findings.degenerate_complementarity(one_free, specs)
    assert "f_zero/clarabel" not in text and "f_zero_c0/clarabel" in text
    assert "f_zero/clarabel inaccurate" in findings.open_failures(one_free, specs)
    # data that do not vanish: no biactivity by construction, and no clause on c = 0
    loaded = changed(one_free, "f_zero_c0", "active_set", problem='{"A": 1.0, "R": 0.45, "c": 0.0, "x0": 0.5}')
    assert findings.degenerate_complementarity(loaded, specs) is None


def test_a_user_limit_is_named_by_the_wall_time_against_the_columns_time_limit(atlas, specs):
    text = findings.user_limit(atlas, specs)
    assert text.startswith("*Iteration or time limit* (A_1e+06/osqp_raw, A_1e+12/osqp_raw, N1001/osqp).")
    assert "max_iter = 10,000 (cvxpy's default, as the columns set none)" in text
    fast, slow = value(atlas, "A_1e+06", "osqp_raw", "total_s"), value(atlas, "N1001", "osqp", "total_s")
    assert f"A_1e+06/osqp_raw ended after {fast:.1f} s, before its time limit of 60 s" in text
    assert "the limit was max_iter. Strength: measured." in text
    assert f"N1001/osqp ran {slow:.0f} s, past its time limit of 60 s" in text and "Strength: explained." in text
    # the slow run made fast and a fast one slow: the limits swap
    swapped = changed(changed(atlas, "N1001", "osqp", total_s=5.0), "A_1e+06", "osqp_raw", total_s=75.0)
    text = findings.user_limit(swapped, specs)
    assert "N1001/osqp ended after 5.0 s, before its time limit of 60 s" in text
    assert "A_1e+06/osqp_raw ran 75 s, past its time limit of 60 s" in text
    # without the columns' options the limit is not known
    assert "the column's limits are not known here. Strength: open." in findings.user_limit(atlas, None)
    no_limit = changed(atlas, "A_1e+06", "osqp_raw", reason="KKT residual 1.0e-03 > 1e-06", status="inaccurate")
    assert "A_1e+06/osqp_raw" not in findings.user_limit(no_limit, specs)


def test_an_as_shipped_column_is_explained_by_its_tolerances_only_where_its_normalized_twin_is_ok(atlas, specs):
    text = findings.absolute_tolerances(atlas, specs)
    assert text.count("_raw") == 10 and "A_1e-12/clarabel_raw" in text and "A_1e+12/scs_raw" in text
    assert "f_zero/clarabel_raw" not in text and "no_contact_N201/osqp_raw" not in text  # their twins fail too
    twin_fails = changed(atlas, "A_1e-12", "clarabel", status="inaccurate")
    assert "A_1e-12/clarabel_raw" not in findings.absolute_tolerances(twin_fails, specs)
    assert "A_1e-12/clarabel_raw inaccurate" in findings.open_failures(twin_fails, specs)
    # a twin that differs in more than the scaling is no controlled comparison
    other = dict(specs, clarabel=dataclasses.replace(specs["clarabel"], options={"normalize": True, "tol": 1e-6}))
    assert "clarabel_raw" not in findings.absolute_tolerances(atlas, other)


def test_a_difference_of_the_exact_columns_below_the_cases_rounding_floor_is_at_the_floor(atlas, specs):
    text = findings.at_rounding_floor(atlas, specs)
    runs = atlas[(atlas["case"] == "no_contact_N201") & atlas["solver"].isin(["active_set", "multigrid"])]
    floor = runs["kkt_threshold"].min()  # the smaller of the two runs' floors
    difference = value(atlas, "no_contact_N201", "multigrid", "diff_to_active_set")
    assert 1e-12 < difference < floor
    assert text.startswith(f"*Rounding floor* (no_contact_N201/multigrid: Δu vs exact {difference:.1e}, "
                           f"floor {floor:.1e}, tolerance 1e-10).")
    assert findings.same_solution_limit(atlas, runs.iloc[1], specs) == (floor, floor)
    # a threshold at the tolerance records no floor; a difference above the floor is not at it
    no_floor = changed(atlas, "no_contact_N201", "active_set", kkt_threshold=1e-10)
    assert findings.at_rounding_floor(no_floor, specs) is None
    assert findings.at_rounding_floor(changed(atlas, "no_contact_N201", "multigrid", diff_to_active_set=2e-9),
                                      specs) is None
    assert findings.at_rounding_floor(atlas, None) is None  # without the tolerances no floor is known


def test_contact_sets_that_differ_under_the_same_solution_are_decided_by_roundoff(atlas, specs):
    text = findings.contact_set_at_roundoff(atlas, specs)
    assert text.startswith("*Contact set decided by round-off* (c_1e+08/multigrid, c_1e+08/multigrid_cold).")
    assert "(active_set 118, multigrid 114, multigrid_cold 114 of 164 nodes)" in text
    assert "|u_i| ≤ 5.8e-14 ‖u_h‖∞" in text and "osqp 129" in text
    # solutions that differ beyond round-off: a different contact set is then no round-off matter
    apart = changed(changed(atlas, "c_1e+08", "multigrid", diff_to_active_set=1e-6),
                    "c_1e+08", "multigrid_cold", diff_to_active_set=1e-6)
    assert findings.contact_set_at_roundoff(apart, specs) is None
    same_set = changed(atlas, "c_1e+08", "multigrid", same_contact_as_active_set=True)
    assert "c_1e+08/multigrid," not in findings.contact_set_at_roundoff(same_set, specs)


def test_every_failure_is_explained_or_listed_as_open(atlas, specs):
    text = findings.open_failures(atlas, specs)
    assert text.startswith("*Not explained*: ") and text.endswith("Strength: open.")
    for case, solver in (("N1001", "scs"), ("no_contact", "scs"), ("no_contact_N201", "osqp")):
        row = atlas[(atlas["case"] == case) & (atlas["solver"] == solver)].iloc[0]
        assert f"{case}/{solver} inaccurate, stationarity {row['kkt_stationarity']:.1e} > 1e-06" in text
    flat = atlas[(atlas["case"] == "N101_jitter0.45") & (atlas["solver"] == "osqp")].iloc[0]
    assert f"N101_jitter0.45/osqp failed ({flat['reason']})" in text  # the flat triangles: open
    assert "N1001/scs" not in findings.open_failures(changed(atlas, "N1001", "scs", status="ok"), specs)
    section = findings.discussion(atlas, specs)
    assert section[:2] == ["## Failures explained", ""] and section[2] == findings.STRENGTHS
    bullets = [line for line in section if line.startswith("- ")]
    assert len(bullets) == len(findings.FINDINGS)
    assert not any(line.startswith("- **") for line in bullets)  # "- **" opens a case line of the page
    explained = {run for line in bullets for run in findings.failures(atlas).apply(findings._run, axis=1)
                 if run in line}
    assert explained == set(findings.failures(atlas).apply(findings._run, axis=1))
    all_ok = atlas[atlas["status"] == "ok"].assign(diff_to_active_set=0.0, same_contact_as_active_set=True)
    assert findings.discussion(all_ok, specs) == []
