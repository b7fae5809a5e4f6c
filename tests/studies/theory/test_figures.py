"""The theory scene's figures (``signorini.studies.theory.figures``): the rate against 1/p with the
expected orders; supercloseness, ``H^{1/2}`` and the ends of the contact set against h; the contact
sets along the unrolled boundary."""

from __future__ import annotations

import numpy as np
import pandas as pd
from helpers import contact_table

from signorini.published import expected_order
from signorini.studies.theory.contact import ends_frame, figure_marks, zoom_windows
from signorini.studies.theory.figures import contact_figure, contact_strip, ends_panel, extra_figure, rate_figure
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
    # the expected orders' sources: the theorem at p = 4 and ∞, inverse estimates between
    assert "Theorem 6.1 for p = 4, ∞" in ax.get_title() and "inverse estimates" in ax.get_title()


def test_the_extra_panels_state_each_curves_slope():
    h = 1.0 / np.array([9.0, 17.0, 33.0])
    table = pd.DataFrame(
        {
            "h": h,
            "H1": 0.3 * h,
            "supercloseness_H1": 0.1 * h**1.5,
            "H12_interpolation": 0.2 * h**1.5,
            "H12_discrete": 0.25 * h**1.5,
            "L4plus": 0.05 * h**2,
            "L4minus": 0.04 * h**2,
            "free_point_offset": 0.3 * h,
        }
    )
    fig = extra_figure(table)
    assert len(fig.axes) == 2  # without the contact sets, no panel of their ends
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert labels[:2] == [r"$\|u-u_h\|_{H^1}$ (slope 1.00)", r"$\|R_hu-u_h\|_{H^1}$ (slope 1.50)"]
    reference = fig.axes[0].get_lines()[2]  # h¹ through 0.7 of the finest H¹ error
    np.testing.assert_allclose(reference.get_ydata(), 0.7 * 0.3 * h[-1] * h / h[-1])
    assert [line.get_label() for line in fig.axes[1].get_lines()][3] == r"$\|(u-u_h)^-\|_{L^4}$ (slope 2.00)"


def _contact(meshes=(9, 17, 33)):
    """A contact table: per N one component from x0 + h/2 to the right edge, and a single node."""
    return contact_table(meshes, 1.25, single_on=meshes)


def test_the_contact_strip_draws_a_row_per_mesh_below_the_exact_set():
    table = _contact()
    ax = contact_strip(table, figure_marks(table))
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == ["exact: $u = 0$", "$N = 9$", "$N = 17$", "$N = 33$"]
    assert [t.get_text() for t in ax.get_xticklabels()][:3] == ["(0, 0)", "bottom", "(1, 0)"]
    bars = [c for c in ax.collections if c.get_label() == "discrete contact set $\\tilde A_h$"]
    assert len(bars) == 1  # one legend entry for all meshes
    singles = [line for line in ax.get_lines() if line.get_label() == "single contact node"]
    assert len(singles) == 1 and singles[0].get_xdata()[0] == 2.5
    texts = [t.get_text() for t in ax.texts]
    assert {"free point $(x_0, 0)$", "$(x_0 - R, 0)$", "$(x_0 + R, 0)$"} <= set(texts)


def test_the_contact_figure_zooms_on_each_end():
    table = _contact()
    table = table[~((table["set"] == "discrete") & (table["length"] == 0))]  # no single node: two ends
    fig = contact_figure(table, figure_marks(table), zoom_windows(table))
    assert len(fig.axes) == 3
    lo, hi = fig.axes[1].get_xlim()
    assert lo < 0.5 + 1 / 66 and 0.5 + 1 / 18 < hi  # the end at the free point on every mesh
    assert "right edge" in fig.axes[2].get_title()


def test_the_ends_panel_draws_each_end_against_h_with_the_corners_in_range():
    table = _contact()
    ax = ends_panel(ends_frame(table), figure_marks(table))
    lines = {line.get_label(): line for line in ax.get_lines()}
    end1 = lines["end 1, on the bottom edge"]
    np.testing.assert_allclose(end1.get_ydata(), [5 / 9, 9 / 17, 17 / 33])
    np.testing.assert_allclose(lines["end 2, on the right edge"].get_ydata(), 1.25)
    assert "corner (1, 0)" in [t.get_text() for t in ax.texts]
    fig = extra_figure(
        pd.DataFrame(
            {
                "h": 1.0 / np.array([9.0, 17.0, 33.0]),
                "H1": [1.0, 0.5, 0.25],
                "supercloseness_H1": [1.0, 0.4, 0.2],
                "H12_interpolation": [1.0, 0.4, 0.2],
                "H12_discrete": [1.0, 0.4, 0.2],
                "L4plus": [1.0, 0.3, 0.1],
                "L4minus": [1.0, 0.3, 0.1],
            }
        ),
        ends_frame(table),
        figure_marks(table),
    )
    assert len(fig.axes) == 3 and fig.axes[2].get_title() == "Ends of the discrete contact set"
