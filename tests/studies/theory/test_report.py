"""The theory report's tables and notes (``signorini.studies.theory.report``)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import contact_table


def test_table2_rows_give_the_eoc_of_each_mesh_pair():
    """``table2_rows``: e = C h^r gives EOC r on every consecutive pair, in the paper's norms
    present, meshes sorted by N; the findings render them with the expected orders."""
    from signorini.published import TABLE2_NORMS
    from signorini.studies.theory.report import table2_rows

    N = np.array([1001, 101, 201, 2001])
    h = 1.0 / N
    errors = pd.DataFrame({"N": N, "h": h, "L4": 3.0 * h**2, "W1inf": 0.7 * h**0.5, "L2": h**2})
    t2 = table2_rows(errors)
    assert list(t2.columns) == ["pair", "L4", "W1inf"]  # only Table 2's norms, in its order
    assert list(t2["pair"]) == ["1/101 → 1/201", "1/201 → 1/1001", "1/1001 → 1/2001"]
    np.testing.assert_allclose(t2["L4"], 2.0, rtol=1e-12)
    np.testing.assert_allclose(t2["W1inf"], 0.5, rtol=1e-12)
    assert set(TABLE2_NORMS) >= {"L4", "Linf", "W14", "W1inf", "H12"}


def test_the_accuracy_of_the_true_values_is_stated_and_a_miss_is_named():
    """theory.md states the largest relative quadrature error estimate of the true values and
    names each value whose levels did not agree to the tolerance."""
    from signorini.studies.theory.report import accuracy_note

    def record(norm, N, value, estimate, converged):
        accuracy = {"error_estimate": estimate, "rtol": 1e-4, "converged": converged}
        return {"norm": norm, "N": N, "value": value, "quadrature_error": accuracy}

    good = [record("L4_true", 101, 2.0, 2e-6, True), record("Linf_true", 201, 1.0, 3e-5, True)]
    assert accuracy_note(good) == (
        "Largest estimated quadrature error: 3.0e-05 relative (Linf_true at N = 201); every value converged to 0.0001."
    )
    note = accuracy_note([*good, record("Linf_true", 2001, 0.5, 6e-4, False)])
    assert "1.2e-03 relative (Linf_true at N = 2001)" in note
    assert "Not converged to 0.0001 within the finest level: Linf_true at N = 2001 (1.2e-03)" in note
    assert accuracy_note([]) == ""


def _errors(slopes: dict[str, float], N=(101, 201, 401, 801)) -> pd.DataFrame:
    """errors.csv of norms e = h^r (r per norm)."""
    N = np.array(N)
    h = 1.0 / N
    return pd.DataFrame({"N": N, "h": h, **{name: h**r for name, r in slopes.items()}})


def test_the_rate_verdict_is_chosen_by_the_gap_and_the_tolerance():
    from signorini.studies.theory.report import RATE_TOL, rate_verdict

    assert rate_verdict(1.97 + 1e-9, 2.0) == "agrees" and rate_verdict(2.0 + RATE_TOL, 2.0) == "agrees"
    assert rate_verdict(2.04, 2.0) == "faster" and rate_verdict(1.96, 2.0) == "slower"
    assert rate_verdict(1.96, 2.0, tol=0.05) == "agrees"


def test_the_rates_table_and_its_csv_carry_each_norms_verdict_and_errors():
    """Exact powers: the orders themselves agree, a perturbed one (L8 at 2 instead of 1.75) is faster,
    a slow one (W14 at 0.9) slower; theory_rates.csv holds the errors per mesh."""
    from signorini.studies.theory.report import _rates_section, rate_rows, rates_frame

    errors = _errors({"L4": 2.0, "L8": 2.0, "Linf": 1.5, "W14": 0.9, "W1inf": 0.5, "H1": 1.0})
    rates = rate_rows(errors)
    text = "\n".join(_rates_section(rates))
    assert "| L4 | 2.000 | 2.000 | 2.000 | 2.000 − ε | agrees (" in text
    assert "| L8 | 2.000 | 2.000 | 2.000 | 1.750 − ε | faster (+0.250) |" in text
    assert "| W14 | 0.900 | 0.900 | 0.900 | 1.000 − ε | slower (-0.100) |" in text
    assert "within ±0.03 (RATE_TOL" in text and "inverse estimates" in text
    frame = rates_frame(errors, rates).set_index("norm")
    assert list(frame.loc["L8", ["verdict"]]) == ["faster"] and frame.loc["L8", "gap"] == pytest.approx(0.25)
    assert frame.loc["W14", "e_N201"] == pytest.approx(201.0**-0.9) and "H1" not in frame.index  # L^p, W^{1,p} only


def _theory_table(super_rate: float = 1.5) -> pd.DataFrame:
    h = 1.0 / np.array([101.0, 201.0, 401.0])
    return pd.DataFrame(
        {
            "N": [101, 201, 401],
            "h": h,
            "H1": h,
            "supercloseness_H1": h**super_rate,
            "H12_interpolation": h**1.5,
            "H12_discrete": 0.5 * h**1.5,
            "L4plus": h**2,
            "L4minus": h**2,
        }
    )


def test_the_h12_bullet_says_what_the_discrete_norm_measures_and_the_verdicts_follow_the_slopes():
    from signorini.studies.theory.report import _supercloseness_section

    text = _supercloseness_section(_theory_table())
    assert "measures v = I_{h/2}u − u_h" in text and "not u − u_h" in text and "no evidence" in text
    assert "Theorem 3.6 gives the order 3/2 − ε: agrees (+0.000)" in text
    assert "Corollary 4.3 and Theorem 6.1 give 3/2 − ε: agrees" in text
    slow = _supercloseness_section(_theory_table(super_rate=1.2))
    assert "Theorem 3.6 gives the order 3/2 − ε: slower (-0.300)" in slow


def test_the_true_h12_column_is_labelled_the_estimate_on_a_fine_rule():
    from signorini.studies.theory.report import TABLE2_TRUE_NOTE, _table2_section, table2_rows

    errors = _errors({"L4_true": 2.0, "H12_true": 1.5})
    lines = _table2_section(table2_rows(errors, ["L4_true", "H12_true"]), "## true", TABLE2_TRUE_NOTE)
    assert lines[2] == "| h | L4_true | H12 estimate (fine rule) |"
    assert "not the H^{1/2}(∂Ω) norm itself" in lines[-2]


def _contact(single_on: int | None = None) -> pd.DataFrame:
    """Contact sets of the scene's shape (one component from x0 + h/2 to (1, 0.2)) on four meshes,
    with a single node at s = 2.5 on mesh ``single_on``."""
    return contact_table((101, 201, 401, 801), 1.2, single_on=(single_on,))


def test_the_contact_section_states_each_verdict_with_its_strength():
    from signorini.studies.theory.report import _contact_section

    text = "\n".join(_contact_section(_contact()))
    assert "## Contact sets and condition (A_h)" in text and "∂Ω \\ (0.05, 0.5) × {0}" in text
    assert "- Consistent with condition (A_h) on these meshes (measured)" in text
    assert "does not converge to 0 on these meshes (measured)" in text and "Why (explained)" in text
    assert "| 801 | 1.248e-03 | 1 | 0 |" in text and "issue" not in text
    broken = "\n".join(_contact_section(_contact(single_on=401)))
    assert "- Condition (A_h) fails on these meshes (measured): a component is a single node" in broken


def test_the_report_stage_writes_the_page_the_rates_csv_and_the_figures(tmp_path):
    from signorini.pipeline.artifacts import save_json
    from signorini.studies.theory.report import report_stage

    table = _theory_table()
    errors = _errors({"L4": 2.0, "Linf": 1.5, "W14": 1.0, "W1inf": 0.5, "H1": 1.0}, N=(101, 201, 401))
    for col in ("H12", "L4plus", "L4minus"):
        errors[col] = table[{"H12": "H12_interpolation"}.get(col, col)]
    errors.to_csv(tmp_path / "errors.csv", index=False)
    jsons = []
    for r in table.itertuples():
        path = tmp_path / f"theory{r.N}.json"
        save_json(
            path,
            {
                "N": r.N,
                "h": r.h,
                "supercloseness_H1": r.supercloseness_H1,
                "H12_discrete": r.H12_discrete,
                "contact": {
                    "n_contact_nodes": 3,
                    "free_point_offset": 0.1,
                    "nearest_to_x0_minus_R": 0.4,
                    "hausdorff": 1.1,
                },
            },
        )
        jsons.append(path)
    _contact().query("N != 801 or N.isna()", engine="python").to_csv(
        tmp_path / "contact_set.csv", index=False, encoding="utf-8"
    )
    names = ("md", "csv", "rates_csv", "rates_pdf", "rates_png", "extra_pdf", "extra_png")
    outs = {k: tmp_path / f"out_{k}.{k.split('_')[-1]}" for k in names}
    report_stage(tmp_path / "errors.csv", jsons, outs, None, tmp_path / "contact_set.csv")
    md = outs["md"].read_text(encoding="utf-8")
    assert "Consistent with condition (A_h)" in md and "Terms (all of them also in docs/glossary.md)" in md
    rates = pd.read_csv(outs["rates_csv"], encoding="utf-8")
    assert list(rates["norm"]) == ["L4", "Linf", "W14", "W1inf"] and "e_N401" in rates.columns
    assert outs["extra_png"].stat().st_size > 10_000
