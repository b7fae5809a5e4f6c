"""Stage ``reproduction`` (``signorini.studies.paper.reproduction``): every published cell as ours |
paper | relative deviation, the largest deviation per norm, and the ``H^{1/2}`` column under both
boundary rules."""

from __future__ import annotations

import pytest

from signorini.studies.paper.reproduction import cells, reproduction_stage


def test_cells_pair_every_published_value_with_ours():
    ours = {"1/101": {"L4": 1.1e-3}, "theo.": {"L4": 2.5}}
    paper = {"1/101": {"L4": 1.0e-3, "W14": 2.0e-2}, "theo.": {"L4": 2.0}}
    rows, worst = cells(ours, paper, lambda v: f"{v:.1e}")
    assert rows == [
        ["1/101", "L4", "1.1e-03", "1.0e-03", "+10.00 %"],
        ["1/101", "W14", "—", "2.0e-02", "—"],  # not computed by us
        ["theo.", "L4", "2.5e+00", "2.0e+00", "+25.00 %"],
    ]
    assert worst.keys() == {"L4"} and abs(worst["L4"] - 0.1) < 1e-12  # the theo. row is left out


def test_the_report_holds_both_tables_the_remarks_and_the_boundary_rules(tmp_path):
    files = {
        "ours1.csv": "h,L4\n1/101,1.1e-3\n1/201,2.6e-4\n",
        "paper1.csv": "# published\nh,L4\n1/101,1.0e-3\n1/201,2.5e-4\n",
        "ours2.csv": "h,L4\n1/201,2.05\nregr.,2.05\ntheo.,2.0\n",
        "paper2.csv": "h,L4\n1/201,2.0\nregr.,2.0\ntheo.,2.0\n",
        "remarks.md": "The meshes are the paper's.\n",
        "h12.csv": "N,h,whole_edges,split\n101,0.0099,1.0e-4,1.1e-4\n",
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    paths = [tmp_path / n for n in ("ours1.csv", "ours2.csv", "paper1.csv", "paper2.csv", "remarks.md")]
    reproduction_stage(*paths, tmp_path / "plain.md")
    plain = (tmp_path / "plain.md").read_text(encoding="utf-8")
    assert "+10.00 %" in plain and "+4.00 %" in plain and "+2.50 %" in plain
    assert "10.00 %" in plain.split("## Table 1")[1].split("\n\n")[1]  # the largest deviation of L⁴
    assert plain.rstrip().endswith("The meshes are the paper's.") and "boundary rule" not in plain
    reproduction_stage(*paths, tmp_path / "h12.md", h12_boundary=tmp_path / "h12.csv")
    h12 = (tmp_path / "h12.md").read_text(encoding="utf-8")
    assert "## The H^{1/2}(∂Ω) column and the boundary rule" in h12
    assert "The split moves `H^{1/2}` by +10.00 % … +10.00 % (relative)." in h12


def test_the_verdicts_and_the_load_rule_follow_the_numbers(tmp_path):
    """With the conventions and the load-rule table, the page states one verdict per column and per
    deviation pattern; a perturbed table flips them."""
    rows = ("1/101", "1/201", "1/301", "1/401", "1/501")
    devs = (0.0008, 0.0493, 0.0068, 0.0068, 0.0095)
    (tmp_path / "paper1.csv").write_text("h,L4\n" + "".join(f"{r},1.0\n" for r in rows), encoding="utf-8")
    (tmp_path / "ours1.csv").write_text(
        "h,L4\n" + "".join(f"{r},{1 + d}\n" for r, d in zip(rows, devs, strict=True)), encoding="utf-8"
    )
    (tmp_path / "t2.csv").write_text("h,L4\ntheo.,2.0\n", encoding="utf-8")
    (tmp_path / "remarks.md").write_text("Conventions.\n", encoding="utf-8")
    conventions = "N,diagonal,quadrature,points,w1p_form,h12_form,dev_L4\n" + "".join(
        f"101,sw_ne,{q},all,components,geometric_full,0.0493\n" for q in ("stroud4_acute1", "dunavant8")
    )
    (tmp_path / "conv.csv").write_text(conventions, encoding="utf-8")
    load = "N,h,norm,default_load,rule_load,relative_change,change_uncertainty,load_change,kkt_worst,quadrature\n"
    load += "101,0.0099,L4,1.0,1.0,1.2e-06,5e-12,2.6e-07,1e-14,stroud4_acute1\n"
    (tmp_path / "load.csv").write_text(load, encoding="utf-8")
    args = [tmp_path / n for n in ("ours1.csv", "t2.csv", "paper1.csv", "t2.csv", "remarks.md")]
    reproduction_stage(*args, tmp_path / "r.md", conventions=tmp_path / "conv.csv", load_rule=tmp_path / "load.csv")
    text = (tmp_path / "r.md").read_text(encoding="utf-8")
    assert "## The load vector's quadrature rule" in text and "| 1/101 | +1.2e-06 | 2.6e-07 |" in text
    assert "(1 of 1 changes are resolved)" in text
    assert "**h = 1/201**: stands out" in text and "a steady offset of +0.68 % … +0.95 %" in text
    assert "explains none of the deviations (*measured*)" in text and "therefore explains" not in text
    steady = [r + "," + str(1.0 + d) for r, d in zip(rows, (0.0008, 0.0493, -0.0068, 0.0068, 0.0095), strict=True)]
    (tmp_path / "ours1.csv").write_text("h,L4\n" + "\n".join(steady) + "\n", encoding="utf-8")
    reproduction_stage(*args, tmp_path / "r.md", conventions=tmp_path / "conv.csv", load_rule=tmp_path / "load.csv")
    assert "a steady offset of" not in (tmp_path / "r.md").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("change", "uncertainty", "printed"),
    [
        (1.2e-06, 5e-12, "+1.2e-06"),  # far above its round-off: two digits
        (-8.7e-10, 3e-11, "-9e-10"),  # the second digit within the round-off: one
        (-8.7e-10, 1.28e-09, "0 ± 2e-09"),  # within it: not resolved, the bound rounded up
        (1.28e-09, 1.28e-09, "0 ± 2e-09"),  # as large as it: not resolved either
    ],
)
def test_a_load_rule_change_is_printed_to_the_digits_its_round_off_leaves(change, uncertainty, printed):
    from signorini.studies.paper.reproduction import resolved_change

    assert resolved_change(change, uncertainty) == printed


def test_an_unresolved_load_rule_change_is_counted_and_shown_as_such(tmp_path):
    """The same cell with a round-off bound above it: printed as 0 ± r and not counted as resolved."""
    from signorini.studies.paper.reproduction import load_rule_section

    load = tmp_path / "load.csv"
    header = "N,h,norm,default_load,rule_load,relative_change,change_uncertainty,load_change,kkt_worst,quadrature\n"
    load.write_text(header + "501,0.002,L4,1.0,1.0,-8.7e-10,1.3e-09,2.2e-09,1e-14,q\n", encoding="utf-8")
    text = load_rule_section(load)
    assert "| 1/501 | 0 ± 2e-09 | 2.2e-09 |" in text and "(0 of 1 changes are resolved)" in text
