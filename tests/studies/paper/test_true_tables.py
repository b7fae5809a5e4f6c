"""The tables of the true norms (``signorini.studies.paper.true_tables``): the gaps of the paper's
conventions and of the printed values to the true norms, what each gap comes from (on perturbed
gaps), the pages' titles and labels, the Markdown rendered from the CSV, and the EOCs of the true
norms.

The stage on synthetic artifacts is tested with the true norms in ``tests/fem/norms/test_true.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from signorini.studies.paper.true_tables import (
    FINE_TARGET,
    ROUNDING,
    TRUE_NORMS_TARGET,
    eoc_rows,
    gap_source,
    markdown_from_csv,
    norm_label,
    pages,
    table2_true_md,
    true_rows,
    true_tables_stage,
)


def test_the_gaps_to_the_true_norm_and_an_unprinted_cell():
    records = [
        {"N": 101, "norm": "L4", "convention": 1.1, "true": 1.0, "estimate": 1e-6},
        {"N": 201, "norm": "L4", "convention": 0.3, "true": 0.25, "estimate": 1e-7},
    ]
    rows = true_rows(records, {"1/101": {"L4": 0.9}})
    assert [r["h"] for r in rows] == ["1/101", "1/201"]
    assert rows[0]["convention_vs_true"] == pytest.approx(0.1) and rows[0]["paper_vs_true"] == pytest.approx(-0.1)
    assert rows[1]["paper"] is None and rows[1]["paper_vs_true"] is None
    assert rows[1]["quadrature_error"] == 1e-7


def test_powers_of_h_give_their_exponents_in_every_row():
    N = [101, 201, 401]
    labels, rows = eoc_rows(N, {"L4_true": [3.0 / n**2 for n in N], "W1inf_true": [0.5 / n**0.5 for n in N]})
    assert labels == ["1/201", "1/401", "regr."]
    np.testing.assert_allclose(rows, [[2.0, 0.5]] * 3, rtol=1e-12)
    conv = {"L4": [3.3 / n**2 for n in N], "W1inf": [0.6 / n**0.5 for n in N]}
    true = {"L4": [3.0 / n**2 for n in N], "W1inf": [0.5 / n**0.5 for n in N]}
    md = table2_true_md(N, conv, true, ["L4", "W1inf"], 1e-4)
    assert "| theo. | 2 − ε | 0.5 − ε |" in md and "| regr. | 2.0000 | 0.5000 |" in md


# --- what each gap comes from, the titles and labels, the Markdown from the CSV ---------------------


def _row(norm: str, gap: float, stated: float = 1e-5, true: float = 2.0) -> dict:
    return {
        "h": "1/101",
        "norm": norm,
        "paper": None,
        "convention": true * (1.0 + gap),
        "true": true,
        "quadrature_error": stated * true,
        "convention_vs_true": gap,
        "paper_vs_true": None,
    }


@pytest.mark.parametrize(
    ("norm", "gap", "source"),
    [
        ("L4", -4e-4, "quadrature"),
        ("L4", 4e-4, "quadrature"),
        ("L4", 5e-6, "within accuracy"),
        ("Linf", -0.05, "point set"),
        ("Linf", 0.0, "attained"),
        ("W1inf", 5e-6, "attained"),
        ("W1inf", 0.05, "above the supremum"),
        ("H12", -5.8e-12, "by construction"),
        ("H12", 1e-3, "quadrature"),
    ],
)
def test_each_gap_is_attributed_by_its_size_against_the_stated_error(norm, gap, source):
    assert gap_source(_row(norm, gap)) == source


def test_the_stated_error_and_the_rounding_set_the_threshold():
    assert gap_source(_row("Linf", -2e-5, stated=1e-5)) == "point set"
    assert gap_source(_row("Linf", -2e-5, stated=3e-5)) == "attained"
    assert gap_source(_row("H12", ROUNDING / 2, stated=0.0)) == "by construction"
    assert gap_source(_row("H12", 2 * ROUNDING, stated=0.0)) == "quadrature"


def test_the_pages_have_distinct_titles_and_name_the_h12_column_an_estimate():
    rows = [_row("L4", -4e-4), _row("H12", 0.0)]
    rows += [{**r, "h": "1/201", "true": r["true"] / 4, "convention": r["convention"] / 4} for r in rows]
    for r in rows[2:]:
        r["quadrature_error"] /= 4
    true_md, _ = pages(rows, ["L4", "H12"], 1e-4, "paper.csv", TRUE_NORMS_TARGET)
    fine_md, fine_eoc = pages(rows, ["L4", "H12"], 1e-4, "paper.csv", FINE_TARGET)
    titles = {md.splitlines()[0] for md in (true_md, fine_md)}
    assert len(titles) == 2 and all("h = 1/101 … 1/201" in t for t in titles)
    assert fine_eoc.splitlines()[0].startswith("# EOCs of the true norms on finer meshes (h = 1/101 … 1/201)")
    assert norm_label("H12") == "H^{1/2}(∂Ω) estimate" and norm_label("L4") == "L⁴(Ω)"
    assert "| H^{1/2}(∂Ω) estimate |" in true_md and "| H^{1/2}(∂Ω) estimate |" in fine_eoc
    assert "so its gap is zero by construction" in true_md and "by construction (2 of 2 meshes)" in true_md
    assert "quad. error (abs.)" in true_md and "largest quad. error (rel.)" in true_md
    # the absolute error of the CSV in the cells, the relative one in the summary
    assert f"| {rows[0]['quadrature_error']:.1e} |" in true_md and "| 1.0e-05 |" in true_md


def test_the_h12_note_says_by_construction_only_where_the_gaps_vanish():
    rows = [_row("H12", 1e-3), {**_row("H12", 0.0), "h": "1/201"}]
    md, _ = pages(rows, ["H12"], 1e-4, "paper.csv")
    assert "so its gap is that of the boundary rule" in md and "zero by construction" not in md
    assert "| quadrature (1 of 2 meshes); by construction (1 of 2) |" in md  # the cells' sources, in order


def test_the_sources_defined_are_those_used():
    md, _ = pages([_row("Linf", -0.05), {**_row("Linf", -0.05), "h": "1/201"}], ["Linf"], 1e-4, "p.csv")
    assert "  - *point set*:" in md and "*quadrature*" not in md and "*attained*" not in md
    assert "For the maxima (L^∞, W^{1,∞}) a bound" in md and "For the integrals" not in md


def test_the_markdown_from_the_csv_is_the_stages(tmp_path):
    """The stage on synthetic artifacts; ``markdown_from_csv`` of its CSV renders its Markdown."""
    from signorini.pipeline.artifacts import save_json

    paper = tmp_path / "paper_table1.csv"
    paper.write_text("# published\nh,L4,Linf\n1/101,1.0e-3,2e-3\n1/201,2.6e-4,7e-4\n", encoding="utf-8")
    Ns = [101, 201]
    values = {"L4": [1.0e-3, 2.5e-4], "L4_true": [1.01e-3, 2.5e-4], "Linf": [2e-3, 7e-4], "Linf_true": [2e-3, 7.4e-4]}
    jsons: dict[str, list[str]] = {}
    for name, vals in values.items():
        for N, value in zip(Ns, vals, strict=True):
            path = tmp_path / f"{name}_{N}.json"
            extra = {"quadrature_error": {"error_estimate": 1e-9, "rtol": 1e-4}} if name.endswith("_true") else {}
            save_json(path, {"N": N, "norm": name, "value": value, **extra})
            jsons.setdefault(name, []).append(str(path))
    outs = {k: tmp_path / f"{k}.{k.split('_')[1]}" for k in ("table1_csv", "table1_md", "table2_csv", "table2_md")}
    true_tables_stage(Ns, jsons, paper, outs, FINE_TARGET)
    md1, md2 = markdown_from_csv(outs["table1_csv"], 1e-4, str(paper), FINE_TARGET)
    assert md1 == outs["table1_md"].read_text(encoding="utf-8")
    assert md2 == outs["table2_md"].read_text(encoding="utf-8")
    assert "| L^∞(Ω) | -5.41 % … +0.00 % |" in md1 and "attained (1 of 2 meshes); point set (1 of 2)" in md1
