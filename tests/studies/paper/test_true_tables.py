"""The tables of the true norms (``signorini.studies.paper.true_tables``): the gaps of the paper's
conventions and of the printed values to the true norms, and the EOCs of the true norms.

The stage on synthetic artifacts is tested with the true norms in ``tests/fem/norms/test_true.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from signorini.studies.paper.true_tables import eoc_rows, table2_true_md, true_rows


def test_the_gaps_to_the_true_norm_and_an_unprinted_cell():
    records = [
        {"N": 101, "norm": "L4", "convention": 1.1, "true": 1.0, "estimate": 1e-6},
        {"N": 201, "norm": "L4", "convention": 0.3, "true": 0.25, "estimate": 1e-7},
    ]
    rows = true_rows(records, {"1/101": {"L4": 0.9}})
    assert [r["h"] for r in rows] == ["1/101", "1/201"]
    assert rows[0]["convention_vs_true"] == pytest.approx(0.1) and rows[0]["paper_vs_true"] == pytest.approx(-0.1)
    assert rows[1]["paper"] is None and rows[1]["paper_vs_true"] is None
    assert rows[1]["quadrature_error"] == 1e-7


def test_powers_of_h_give_their_exponents_in_every_row():
    N = [101, 201, 401]
    labels, rows = eoc_rows(N, {"L4_true": [3.0 / n**2 for n in N], "W1inf_true": [0.5 / n**0.5 for n in N]})
    assert labels == ["1/201", "1/401", "regr."]
    np.testing.assert_allclose(rows, [[2.0, 0.5]] * 3, rtol=1e-12)
    conv = {"L4": [3.3 / n**2 for n in N], "W1inf": [0.6 / n**0.5 for n in N]}
    true = {"L4": [3.0 / n**2 for n in N], "W1inf": [0.5 / n**0.5 for n in N]}
    md = table2_true_md(N, conv, true, ["L4", "W1inf"], 1e-4)
    assert "| theo. | 2 − ε | 0.5 − ε |" in md and "| regr. | 2.0000 | 0.5000 |" in md
