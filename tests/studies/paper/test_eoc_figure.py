"""The EOCs against h (``signorini.studies.paper.eoc_figure``): the two tables joined at their shared
mesh, the EOCs of ``fem.convergence.eoc`` drawn at the finer mesh, the expected orders, the stage."""

from __future__ import annotations

import numpy as np
import pytest

from signorini.fem.convergence import eoc
from signorini.published import TABLE2_NORMS, expected_rate
from signorini.studies.paper.eoc_figure import (
    KINDS,
    PANELS,
    eoc_against_h_stage,
    eoc_figure,
    eoc_panel,
    eoc_series,
    read_errors,
)

RATES = {"L4": 2.0, "L16": 1.7, "Linf": 1.5, "W14": 1.0, "W116": 0.63, "W1inf": 0.5, "H12": 1.45}


def write_table(path, Ns, norms=TABLE2_NORMS, scale=1.0, shift=0.0):
    """An errors CSV (the columns eoc_figure reads, and the others) of e = C h^r, the convention
    ``shift`` (relative) off the true norm."""
    lines = ["h,norm,paper,convention,true,quadrature_error,convention_vs_true,paper_vs_true"]
    for N in Ns:
        for norm in norms:
            true = scale * (1.0 / N) ** RATES[norm]
            lines.append(f"1/{N},{norm},,{true * (1.0 + shift)!r},{true!r},1e-12,{shift!r},")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.fixture
def tables(tmp_path):
    paper = write_table(tmp_path / "true.csv", [101, 201, 301, 401, 501])
    fine = write_table(tmp_path / "fine.csv", [501, 1001, 2001], scale=1.5)  # its 1/501 row differs
    return paper, fine


def test_the_tables_join_at_their_shared_mesh_read_from_the_first(tables):
    frame = read_errors(*tables)
    assert list(frame["N"].unique()) == [101, 201, 301, 401, 501, 1001, 2001]
    row = frame[(frame["N"] == 501) & (frame["norm"] == "L4")]
    assert len(row) == 1 and row["table"].iloc[0] == 0
    assert row["true"].iloc[0] == pytest.approx((1 / 501) ** 2)


def test_the_eocs_are_those_of_fem_convergence_at_the_finer_mesh(tables):
    frame = read_errors(*tables)
    h, rates = eoc_series(frame, "W116", "true")
    sub = frame[frame["norm"] == "W116"]
    np.testing.assert_array_equal(h, 1.0 / np.array([201, 301, 401, 501, 1001, 2001]))
    np.testing.assert_array_equal(rates, eoc(sub["h"].to_numpy(), sub["true"].to_numpy())[1:])
    # a power of h gives its exponent, except across the join, where the second table's scale enters
    assert rates[:4] == pytest.approx([RATES["W116"]] * 4, rel=1e-12)
    assert rates[4] != pytest.approx(RATES["W116"], rel=1e-3)


def test_each_norm_draws_true_convention_and_its_expected_order(tables):
    frame = read_errors(*tables)
    ax = eoc_panel(frame, ("L4", "Linf"))
    lines = ax.get_lines()
    assert len(lines) == 2 * (len(KINDS) + 1)  # per norm: convention, true, expected order
    for k, norm in enumerate(("L4", "Linf")):
        conv, true, theory = lines[3 * k : 3 * k + 3]
        assert conv.get_linestyle() == "--" and true.get_linestyle() == "-" and theory.get_linestyle() == ":"
        np.testing.assert_array_equal(true.get_ydata(), eoc_series(frame, norm, "true")[1])
        np.testing.assert_array_equal(conv.get_ydata(), eoc_series(frame, norm, "convention")[1])
        assert set(theory.get_ydata()) == {expected_rate(norm)}
        assert conv.get_color() == true.get_color() == theory.get_color()
    assert ax.get_xscale() == "log"
    assert [t.get_text() for t in ax.get_xticklabels()][-1] == "1/201"


def test_the_figure_has_a_panel_per_family_and_shades_the_paper_pairs(tables):
    frame = read_errors(*tables)
    fig = eoc_figure(frame, paper_finest=501)
    axes = fig.axes
    assert len(axes) == len(PANELS) and sum(len(norms) for _, norms in PANELS) == len(TABLE2_NORMS)
    xs = axes[0].patches[0].get_path().transformed(axes[0].patches[0].get_patch_transform()).vertices[:, 0]
    assert 1 / 1001 < xs.min() < 1 / 501 < 1 / 201 < xs.max() < 1 / 101


def test_the_stage_writes_the_figure_and_refuses_a_table_without_a_norm(tables, tmp_path):
    outs = {"pdf": tmp_path / "e.pdf", "png": tmp_path / "e.png"}
    eoc_against_h_stage(*tables, outs)
    assert outs["png"].stat().st_size > 10_000 and outs["pdf"].read_bytes().startswith(b"%PDF")
    short = write_table(tmp_path / "short.csv", [101, 201], norms=("L4", "W14"))
    with pytest.raises(ValueError, match="H12"):
        eoc_against_h_stage(short, short, outs)
