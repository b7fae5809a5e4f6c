"""The digits of the rendered numbers (``signorini.formatting``)."""

from __future__ import annotations

import math

import pytest

from signorini.formatting import (
    ceil_sig,
    certified_decimals,
    certified_digits,
    fmt_factor,
    fmt_fit,
    fmt_ratio,
    fmt_timed,
    round_sig,
    sci_md,
    sig_csv,
)


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


@pytest.mark.parametrize(
    ("x", "bound"), [(1.2760455757412132e-09, 2e-09), (2e-09, 2e-09), (9.5e-12, 1e-11), (0.30000000000000004, 0.4)]
)
def test_ceil_sig_rounds_a_bound_up_to_one_digit(x, bound):
    assert ceil_sig(x) == bound and ceil_sig(x) >= x


def test_ceil_sig_leaves_what_has_no_digit_to_round():
    assert ceil_sig(0.0) == 0.0 and ceil_sig(math.inf) == math.inf and math.isnan(ceil_sig(math.nan))


def test_round_sig_is_what_every_format_prints():
    x = 2.3948826503649732e-05
    assert round_sig(x, 5) == 2.3949e-05 and sig_csv(round_sig(x, 5), 5) == "2.3949e-05"
    assert sci_md(round_sig(x, 3), 2) == "2.39·10⁻⁵"
    assert round_sig(9.99996, 5) == 10.0 and sci_md(10.0, 4) == "1.0000·10¹"


def test_times_ratios_and_exponents_are_printed_with_their_intervals():
    assert fmt_timed({"value": 1.58, "lo": 1.32, "hi": 1.82, "interval": True, "samples": 5}) == "1.6 s (1.3–1.8)"
    assert fmt_timed({"value": 12.4, "lo": 0, "hi": 0, "interval": False, "samples": 1}) == "12.4 s (1 sample)"
    assert fmt_ratio({"value": 0.9, "lo": 0.7, "hi": 1.4, "interval": True, "verdict": "tie"}) == "tie (×0.70–1.4)"
    assert fmt_ratio({"value": 2.4, "lo": 2.2, "hi": 2.8, "interval": True, "verdict": "above"}) == "×2.4 (2.2–2.8)"
    assert fmt_fit({"value": -0.95, "lo": -0.97, "hi": -0.93, "interval": True}) == "−0.95 (−0.97 to −0.93)"
    assert fmt_fit({"value": 1.05, "lo": 1.01, "hi": 1.11, "interval": True}) == "1.05 (1.01–1.11)"
    assert fmt_ratio({"value": 2.4, "lo": 0.0, "hi": 0.0, "interval": False, "verdict": "undetermined"}) == (
        "×2.4 (undetermined: one sample each)"
    )
    assert fmt_factor(0.821) == "0.82" and fmt_factor(12.4) == "12" and fmt_timed({"value": float("nan")}) == "—"


def test_a_tex_subscript_stays_upright_in_markdown():
    """``‖e‖_{L²(∂Ω)}^{1/2} ‖e‖_{H¹(∂Ω)}^{1/2}`` as written: CommonMark (the report's renderer) took the
    two ``_`` for an emphasis and set the text between them in italics; code spans are left alone."""
    from markdown_it import MarkdownIt

    from signorini.formatting import markdown_text

    text = "estimate ‖e‖_{L²(∂Ω)}^{1/2} ‖e‖_{H¹(∂Ω)}^{1/2}, not `‖e‖_{H¹}` nor `<norm>_true`; u_h^s‖_{L⁴}"
    render = MarkdownIt("commonmark").render
    assert "<em>" in render(text)
    escaped = markdown_text(text)
    assert "<em>" not in render(escaped)
    assert render(escaped).count("_{") == 4 and "<code>‖e‖_{H¹}</code>" in render(escaped)
    assert markdown_text(escaped.replace("\\_{", "_{")) == escaped and markdown_text("no subscript") == "no subscript"
