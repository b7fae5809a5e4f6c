"""The atlas as a figure (``signorini.studies.stability.figures``): the case × solver status grid
and the panels beside it."""

from __future__ import annotations

from matplotlib.colors import to_hex

from signorini.studies.stability.figures import STATUS_COLOURS, atlas_figure, status_grid
from signorini.studies.stability.table import atlas_table


def test_the_grid_colours_each_cell_by_its_status(small_atlas):
    """ok green; bad input refused with a clear error blue (the expected outcome); a solver the
    case did not run grey; the failed cell names the error class."""
    df = atlas_table(*small_atlas)
    ax = status_grid(df, ["active_set", "osqp"])
    colours = [to_hex(p.get_facecolor()) for p in ax.patches]
    want = [STATUS_COLOURS[s] for s in ("ok", "not run", "ok", "not run", "rejected", "not run")]
    assert colours == want  # row by row: A_10, A_1e-6, bad_spd
    texts = [t.get_text() for t in ax.texts]
    assert "BadInput" in texts and sum(t.startswith("k ") for t in texts) == 2
    assert [t.get_text() for t in ax.get_yticklabels()] == ["A_10  [scaling]", "A_1e-6  [scaling]",
                                                            "bad_spd  [bad_input]"]
    fig = atlas_figure(df, ["active_set"])
    grid, kkt, diff = fig.axes[:3]  # the grid, then the scaling sweep against the amplitude A
    assert grid.get_title().startswith("stability atlas")
    (line,) = kkt.get_lines()
    assert list(line.get_xdata()) == [1e-6, 10.0]  # the scaling cases, sorted by A
    assert list(diff.get_lines()[0].get_xdata()) == [1e-6, 10.0]
