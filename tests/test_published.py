"""The paper's facts (``signorini.published``): the expected rates of every norm."""

from __future__ import annotations

import math

import pytest

from signorini.fem.norms.names import parse_norm_name
from signorini.published import THEORETICAL_ORDERS, expected_rate


@pytest.mark.parametrize(
    "norm, order",
    [("L2", 2.0), ("L4", 2.0), ("L6", 1.5 + 2 / 6), ("Linf", 1.5), ("W12", 1.0), ("W1inf", 0.5), ("H1", 1.0),
     ("H12", 1.5), ("L4plus", 2.0), ("L4_true", 2.0), ("L2boundary", None)],
)
def test_expected_rate_of_every_family_of_the_grammar(norm, order):
    parse_norm_name(norm)  # in the grammar
    got = expected_rate(norm)
    assert got == (pytest.approx(order) if order is not None else None)
    if norm in THEORETICAL_ORDERS:
        assert math.isclose(THEORETICAL_ORDERS[norm], got)


def test_expected_rates():
    assert expected_rate("L4") == 2.0 and expected_rate("L2") == 2.0
    assert expected_rate("L16") == pytest.approx(1.625)
    assert expected_rate("Linf") == 1.5 and expected_rate("W1inf") == 0.5
    assert expected_rate("W116") == pytest.approx(0.625)
    assert expected_rate("H12") == 1.5 and expected_rate("H1") == 1.0  # Table 2's theo. row; W^{1,2}
    assert expected_rate("L4plus") == 2.0 and expected_rate("L2boundary") is None
