"""The digits of the rendered numbers (``signorini.formatting``)."""

from __future__ import annotations

import math

import pytest

from signorini.formatting import certified_decimals, certified_digits, round_sig, sci_md, sig_csv


@pytest.mark.parametrize(
    ("value", "uncertainty", "digits"),
    [
        (2.3948826e-05, 1e-12, 5),  # 7 certified, the paper's 5 printed
        (2.3948826e-05, 4e-9, 3),  # 2.39e-05: the unit 1e-7 of the 3rd digit exceeds 4e-9, of the 4th not
        (2.3948826e-05, 3e-5, 1),  # nothing certified: one digit, never zero
        (0.48670603, 0.0, 5),  # exact
        (0.0, 1e-3, 5),
        (1.0, math.nan, 1),
    ],
)
def test_certified_digits(value, uncertainty, digits):
    assert certified_digits(value, uncertainty) == digits


def test_certified_decimals():
    assert [certified_decimals(u) for u in (1e-7, 3e-4, 0.05, 2.0, 0.0)] == [4, 3, 1, 0, 4]


def test_round_sig_is_what_every_format_prints():
    x = 2.3948826503649732e-05
    assert round_sig(x, 5) == 2.3949e-05 and sig_csv(round_sig(x, 5), 5) == "2.3949e-05"
    assert sci_md(round_sig(x, 3), 2) == "2.39·10⁻⁵"
    assert round_sig(9.99996, 5) == 10.0 and sci_md(10.0, 4) == "1.0000·10¹"
