"""The work-precision study's figures (``signorini.studies.work_precision.figures``): the series
drawn (chosen by their selected runs), solver families, and the cost of accuracy of the exact
solver with a colour and marker of its own for every series."""

from __future__ import annotations

import dataclasses

from signorini.studies.work_precision import figures as wpfig
from signorini.studies.work_precision.figures import cost_of_accuracy, cost_panel, family
from signorini.studies.work_precision.table import Run


def test_families(run_row):
    runs = [run_row(101, "x", "1e-08", [1.0], solver=s) for s in ("petsc_snes", "petsc_tao", "OSQP")]
    assert [family(r) for r in runs] == ["PETSc SNES VI", "PETSc TAO", "OSQP"]


def test_the_cost_panel_fits_the_slope_of_each_error_against_the_total_time(measurements):
    """Assembly + solve grow like N (0.011 N s): L⁴ ∝ N⁻² and W^{1,4} ∝ N⁻¹ have slopes −2 and −1."""
    ax = cost_panel(measurements)
    lines = ax.get_lines()
    assert [line.get_label() for line in lines] == [r"$L^4$ (slope -2.00)", r"$W^{1,4}$ (slope -1.00)"]
    assert list(lines[0].get_xdata()) == [0.11, 0.22, 0.44]  # the exact solver's rows only
    assert len({line.get_marker() for line in lines}) == 2
    fig = cost_of_accuracy(measurements)
    assert len(fig.axes) == 2 and fig.axes[1].get_title() == "Where the time goes"


def _families(run_row) -> list[Run]:
    """Four exact configurations, four TAO methods, four QP solvers and a failing one, on N = 101, 201."""
    rows = []
    for N in (101, 201):
        rows += [
            run_row(N, "ours", "exact", [1.0], start="cascade"),
            run_row(N, "ours_cold", "exact", [4.0]),
            run_row(N, "ours_superlu", "exact", [2.0], start="cascade"),
            run_row(N, "ours_mg", "exact", [2.0], start="cascade", solver="multigrid"),
        ]
        # four TAO methods: the one whose selected run takes the fewest CPU seconds is drawn
        rows += [run_row(N, f"tao{k}", "1e-08", [4.0 - k], solver="petsc_tao") for k in range(4)]
        rows += [run_row(N, f"qp{k}", "1e-08", [1.0], solver=f"QP{k}") for k in range(4)]  # one family each
        rows.append(run_row(N, "broken", "1e-08", [1.0], solver="QPX", status="failed"))
    return [dataclasses.replace(r, alg={"L4": 1e-9, "W14": 1e-9}) for r in rows]


def test_figure_draws_the_fastest_configuration_per_family_with_the_legend_below(run_row):
    """Exact solvers plus one configuration per solver family (the fastest selected run on the
    finest mesh), at most eight, Okabe–Ito colours, legends below the axes."""
    df = _families(run_row)
    series = wpfig.figure_series(df, ["L4"])
    assert len(series) == wpfig.MAX_SERIES == 8
    # beyond 8: one exact configuration per route and start (a backend variant goes, another route stays)
    assert series[:3] == ["ours", "ours_cold", "ours_mg"] and "ours_superlu" not in series
    assert "tao3" in series and not {"tao0", "tao1", "tao2"} & set(series)
    assert "broken" not in series  # a family without one ok run
    fig = wpfig.work_precision_figure(df, [101, 201])
    colours = {line.get_color() for ax in fig.axes for line in ax.get_lines() if line.get_marker() not in ("", "None")}
    assert colours <= set(wpfig.OKABE_ITO)
    fig.canvas.draw()
    lowest = min(ax.get_window_extent().y0 for ax in fig.axes)
    assert all(leg.get_window_extent().y1 < lowest for leg in fig.legends)  # no legend over a panel


def test_an_inaccurate_run_does_not_make_a_configuration_the_fastest_of_its_family(run_row, changed):
    df = changed(_families(run_row), {"config": "tao3", "N": 201}, status="inaccurate")
    assert "tao2" in wpfig.figure_series(df, ["L4"]) and "tao3" not in wpfig.figure_series(df, ["L4"])


def test_figure_keeps_the_fastest_exact_configuration_of_each_start_when_routes_are_too_many(run_row):
    """Four exact configurations (two routes × two starts) and five solver families: beyond eight
    series, per start the exact configuration with the fewest CPU seconds on the finest mesh
    stays (the direct route from the cascade, the multigrid route from the cold start)."""
    rows = []
    for N in (101, 201):
        rows += [
            run_row(N, "ours", "exact", [1.0], start="cascade"),
            run_row(N, "ours_mg", "exact", [2.0], start="cascade", solver="multigrid"),
            run_row(N, "ours_cold", "exact", [4.0 if N == 201 else 1.0]),
            run_row(N, "ours_mg_cold", "exact", [1.5], solver="multigrid"),
        ]
        rows += [run_row(N, f"qp{k}", "1e-08", [1.0], solver=f"QP{k}") for k in range(5)]
    series = wpfig.figure_series(rows, ["L4"])
    assert [c for c in series if not c.startswith("qp")] == ["ours", "ours_mg_cold"]
    assert len(series) == 7


def test_every_series_of_the_time_panel_has_its_own_colour_and_marker(run_row):
    """The exact configurations the work-precision figure leaves out get colours of their own; the
    drawn peer keeps its colour from that figure; with the assembly, no two series look alike."""
    df = _families(run_row)
    series = wpfig.time_series(df, ["L4"])
    assert list(series) == ["ours", "ours_cold", "ours_superlu", "ours_mg", "tao3"]
    drawn = wpfig._colors(wpfig.figure_series(df, ["L4"]))
    assert series["tao3"]["color"] == drawn["tao3"] and series["tao3"]["peer"]
    assert series["ours_superlu"]["color"] in wpfig.EXTRA_COLORS
    styles = [(v["color"], v["marker"]) for v in series.values()] + [(wpfig.ASSEMBLY["color"], "s")]
    assert len({c for c, _ in styles}) == len(styles) and len({m for _, m in styles}) == len(styles)
    ax = wpfig.time_panel(df)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[0] == "assembly (mesh, A, b)" and labels[-1] == r"$\propto$ unknowns" and len(labels) == 7
