"""Figures 2 and 3 (``signorini.studies.paper.figures``): the surfaces of ``u`` and ``f``, the
errors with reference slopes of their expected orders, the rounding of the drawn fields."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from signorini.published import expected_rate
from signorini.studies.paper.figures import figure2, figure3, rounded_fields


def test_figure3_draws_each_error_with_a_reference_slope_of_its_expected_order():
    h = 1.0 / np.array([101.0, 201.0, 401.0])
    errors = pd.DataFrame({"h": h, "L4": 3e-1 * h**2.1, "W14": 2e-1 * h**0.9})
    lines = figure3(errors).get_lines()
    assert len(lines) == 4  # per norm: the errors and the dashed reference
    for (data, ref), norm in zip([lines[0:2], lines[2:4]], ["L4", "W14"], strict=True):
        np.testing.assert_array_equal(data.get_ydata(), errors[norm])
        assert ref.get_linestyle() == "--" and ref.get_color() == data.get_color()
        x, y = np.log(ref.get_xdata()), np.log(ref.get_ydata())
        np.testing.assert_allclose(np.diff(y) / np.diff(x), expected_rate(norm), rtol=1e-12)
        assert ref.get_ydata()[0] == pytest.approx(0.5 * errors[norm].iloc[0])  # through half the coarsest


def test_figure2_draws_two_surfaces_and_the_fields_are_drawn_rounded():
    t = np.linspace(0.0, 1.0, 5)
    X, Y = np.meshgrid(t, t)
    fields = {"x": X, "y": Y, "u": X * (1 + 1e-9 * Y), "f": np.sin(X + Y), "n": np.arange(3)}
    rounded = rounded_fields(fields, digits=6)
    np.testing.assert_array_equal(rounded["u"], X)  # a change in the 10th digit is gone
    assert rounded["f"][1, 2] == float(f"{np.sin(0.75):.5e}") and rounded["n"] is fields["n"]
    fig = figure2(rounded)
    assert len(fig.axes) == 2 and all(ax.name == "3d" for ax in fig.axes)
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[0] == "solution $u$"
    assert "c\\,u$" in titles[1] and "$c$: the reaction coefficient" in titles[1]  # the constant it shows, defined
