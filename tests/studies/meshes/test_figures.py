"""The mesh-family study's figure (``signorini.studies.meshes.figures``): drawn on given axes, one
marker series per family on each panel where it belongs, the expected orders as bars, the errors
against the unknowns."""

from __future__ import annotations

from matplotlib.figure import Figure

from signorini.studies.meshes.figures import rates_figure


def test_the_figure_draws_each_family_on_given_axes(study):
    scenes, table = study()
    axes = Figure().subplots(2, 2)
    assert rates_figure(table, scenes, axes) is axes
    (slopes, orders), (l4, w14) = axes
    # the graded family is not quasi-uniform: only in the order against the unknowns
    assert len(slopes.lines) == 2 and len(orders.lines) == 3
    assert [t.get_text() for t in orders.get_xticklabels()] == ["L4_true", "W1inf_true", "H12"]
    assert len(orders.collections) == 1  # the expected orders
    # the made-up scenes have L4_true but no W14_true: one curve per family, or none
    assert len(l4.lines) == 3 and not w14.lines and l4.get_xscale() == "log"
    legend = [t.get_text() for t in slopes.figure.legends[0].get_texts()]
    assert legend == [s.label for s in scenes] + ["Theorem 6.1 (order − ε)"]
