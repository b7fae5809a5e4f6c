"""The theory scene's figures (``signorini.studies.theory.figures``): the rate against 1/p with the
theoretical curves, and supercloseness, ``H^{1/2}`` and the contact set against h."""

from __future__ import annotations

import numpy as np
import pandas as pd

from signorini.published import expected_order
from signorini.studies.theory.figures import extra_figure, rate_figure
from signorini.studies.theory.report import rate_rows


def test_the_rates_are_drawn_against_1_over_p_beside_the_theory():
    """Errors of exact powers of h: each measured slope is its exponent, drawn at 1/p."""
    N = np.array([9, 17, 33, 65])
    h = 1.0 / N
    errors = pd.DataFrame({"N": N, "h": h, "L2": h**2.0, "L8": h**1.75, "Linf": h**1.5, "W12": h, "W1inf": h**0.5})
    rates = rate_rows(errors)
    ax = rate_figure(rates)
    lines = {line.get_label(): line for line in ax.get_lines()}
    theory = lines["theory $L^p$: $2$, $3/2+2/p$"]
    q = theory.get_xdata()
    np.testing.assert_allclose(theory.get_ydata()[q == 0.25], expected_order("L", 4.0))
    measured = lines["$L^p$: regression, all meshes"]
    np.testing.assert_allclose(measured.get_xdata(), [1 / 2, 1 / 8, 0.0])  # L2, L8, Linf: by p
    np.testing.assert_allclose(measured.get_ydata(), [2.0, 1.75, 1.5], rtol=1e-12)
    np.testing.assert_allclose(lines["$W^{1,p}$: regression, finest 3"].get_ydata(), [1.0, 0.5], rtol=1e-12)


def test_the_extra_panels_state_each_curves_slope():
    h = 1.0 / np.array([9.0, 17.0, 33.0])
    table = pd.DataFrame({
        "h": h, "H1": 0.3 * h, "supercloseness_H1": 0.1 * h**1.5, "H12_interpolation": 0.2 * h**1.5,
        "H12_discrete": 0.25 * h**1.5, "L4plus": 0.05 * h**2, "L4minus": 0.04 * h**2, "free_point_offset": 0.3 * h,
    })
    fig = extra_figure(table)
    assert len(fig.axes) == 3
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert labels[:2] == [r"$\|u-u_h\|_{H^1}$ (slope 1.00)", r"$\|R_hu-u_h\|_{H^1}$ (slope 1.50)"]
    reference = fig.axes[0].get_lines()[2]  # h¹ through 0.7 of the finest H¹ error
    np.testing.assert_allclose(reference.get_ydata(), 0.7 * 0.3 * h[-1] * h / h[-1])
    assert [line.get_label() for line in fig.axes[1].get_lines()][3] == r"$\|(u-u_h)^-\|_{L^4}$ (slope 2.00)"
