"""The theory report's tables and notes (``signorini.studies.theory.report``)."""

from __future__ import annotations

import numpy as np
import pandas as pd


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
