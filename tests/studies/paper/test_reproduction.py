"""Stage ``reproduction`` (``signorini.studies.paper.reproduction``): every published cell as ours |
paper | relative deviation, the largest deviation per norm, and the ``H^{1/2}`` column under both
boundary rules."""

from __future__ import annotations

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
