"""The work-precision study's figures (``signorini.studies.work_precision.figures``): solver
families, and the cost of accuracy of the exact solver.

The work-precision figure itself is tested in ``tests/studies/work_precision/test_measure.py``.
"""

from __future__ import annotations

from signorini.studies.work_precision.figures import cost_of_accuracy, cost_panel, family, is_peer_table


def test_families_and_peer_tables(measurements):
    assert [family(s) for s in ("petsc_snes", "petsc_tao", "OSQP")] == ["PETSc SNES VI", "PETSc TAO", "OSQP"]
    assert not is_peer_table(measurements)
    assert is_peer_table(measurements.assign(solver="petsc_tao"))


def test_the_cost_panel_fits_the_slope_of_each_error_against_the_total_time(measurements):
    """Assembly + solve grow like N (0.011 N s): L⁴ ∝ N⁻² and W^{1,4} ∝ N⁻¹ have slopes −2 and −1."""
    ax = cost_panel(measurements)
    lines = ax.get_lines()
    assert [line.get_label() for line in lines] == [r"$L^4$ (slope -2.00)", r"$W^{1,4}$ (slope -1.00)"]
    assert list(lines[0].get_xdata()) == [0.11, 0.22, 0.44]  # the exact solver's rows only
    fig = cost_of_accuracy(measurements)
    assert len(fig.axes) == 2 and fig.axes[1].get_title() == "Where the time goes"
