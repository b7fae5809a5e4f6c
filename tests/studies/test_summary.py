"""The summary's findings (``signorini.studies.summary``): each number recomputed independently from
the committed CSVs, and each condition checked on perturbed data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from signorini.studies import summary as sm
from signorini.studies.paper.reference import read_table_csv

ROOT = Path(__file__).resolve().parents[2]
FIG = "paper_figures"
TRUE, FINE, FINEST = f"{FIG}/table1_true.csv", f"{FIG}/table1_fine.csv", f"{FIG}/table1_finest.csv"


@pytest.fixture(scope="module")
def cells() -> pd.DataFrame:
    return sm._true_cells(TRUE, FINE)


def test_point_set_numbers_come_from_the_true_tables(cells):
    found = sm.point_set_findings(cells, ())
    frame = pd.read_csv(TRUE)
    w1inf = frame[frame["norm"] == "W1inf"]
    gap = (w1inf["paper"] - w1inf["true"]) / w1inf["true"]
    assert f"{100 * gap.min():+.2f} % … {100 * gap.max():+.2f} %" in found[1].text
    assert found[1].strength == "explained"  # the conventions' points give the same gap
    first = pd.read_csv(f"{FIG}/table2_true.csv").set_index("h").loc["1/201", "Linf_true"]
    assert f"the true norm's is {first:.2f}" in found[2].text


def test_point_set_verdicts_flip_on_perturbed_data(cells):
    honest = cells.copy()
    honest["paper"] = np.where(honest["paper"].notna(), honest["true"], np.nan)
    found = sm.point_set_findings(honest, ())
    assert all("misses the supremum" not in v.text for v in found) and len(found) == 2  # no EOC artifact either
    other = cells.copy()
    other["convention"] = other["true"]  # the conventions no longer reproduce the published gap
    assert sm.point_set_findings(other, ())[1].strength == "measured"


def test_l16_numbers(cells):
    text = sm.l16_findings(cells, ())[0].text
    frame = pd.concat([pd.read_csv(TRUE), pd.read_csv(FINE)])
    l16 = frame[frame["norm"] == "L16"]
    assert f"{-100 * l16['convention_vs_true'].min():.2f} %" in text
    fine = pd.read_csv(f"{FIG}/table2_fine.csv").set_index("h")
    assert fine.loc["1/1001", "L16_true"] == pytest.approx(1.625, abs=sm.RATE_TOLERANCE)
    assert "only from h = 1/1001 on" in text


def test_rates_numbers_match_table2_fine(cells):
    found = sm.rate_findings(cells, ())
    fine = pd.read_csv(f"{FIG}/table2_fine.csv").set_index("h")
    assert f"L⁴(Ω) {fine.loc['1/4001', 'L4_true']:.3f}" in found[0].text
    h12 = found[-1]
    assert h12.strength == "open" and f"EOC {fine.loc['1/4001', 'H12_true']:.3f}" in h12.text
    rows = cells[cells["norm"] == "H12"]
    h = 1.0 / rows["N"].to_numpy(float)
    beta = np.polyfit(np.log(-np.log(h)), np.log(rows["true"].to_numpy()) - 1.5 * np.log(h), 1)[0]
    assert f"β = {beta:.2f}" in h12.text
    trend = ", ".join(f"{fine.loc[f'1/{N}', 'H12_true']:.4f}" for N in (1001, 2001, 4001))
    assert f"the EOCs from h = 1/1001 to 1/4001: {trend}" in h12.text


def test_the_finest_meshes_carry_the_h12_trend_one_mesh_further():
    """With ``table1_finest.csv`` the H^{1/2} finding is at h = 1/8001 and lists four EOCs from 1/1001,
    the last those of ``table2_finest.csv``; the norms on fewer meshes keep h = 1/4001."""
    found = sm.rate_findings(sm._true_cells(TRUE, FINE, FINEST), ())
    finest = pd.read_csv(f"{FIG}/table2_finest.csv").set_index("h")
    h12 = found[-1].text
    assert h12.startswith(f"H^{{1/2}}(∂Ω): EOC {finest.loc['1/8001', 'H12_true']:.3f} at h = 1/8001")
    assert "to 1/8001: " in h12 and h12.count(", 1.4") >= 3
    assert found[0].text.startswith("at h = 1/8001") and "L¹⁶(Ω) 1.624 (h = 1/4001)" in found[0].text


def test_a_norm_on_fewer_meshes_is_named_with_its_own_finest_mesh(cells):
    """One mesh further for L⁴ alone (as the scene ``finest`` adds three norms at h = 1/8001): the
    finding is at h = 1/8001, and the norms whose finest mesh is h = 1/4001 say so."""
    last = cells[(cells["norm"] == "L4") & (cells["N"] == 4001)].iloc[0]
    further = last.copy()
    further["N"], further["h"], further["true"] = 8001, 1 / 8001, last["true"] * (4001 / 8001) ** 2
    found = sm.rate_findings(pd.concat([cells, further.to_frame().T], ignore_index=True), ())
    assert found[0].text.startswith("at h = 1/8001 the EOCs")
    assert "L⁴(Ω) 2.000," in found[0].text and "L¹⁶(Ω) 1.624 (h = 1/4001)" in found[0].text
    assert "H^{1/2}" not in found[0].text and "at h = 1/4001" in found[-1].text

def test_a_rate_off_its_order_is_listed_apart(cells):
    moved = cells.copy()
    last = moved[moved["norm"] == "L4"].index[-1]
    moved.loc[last, "true"] *= 1.2  # the last L4 EOC falls well below 2
    found = sm.rate_findings(moved, ())
    assert "L⁴(Ω)" not in found[0].text and any(v.text.startswith("L⁴(Ω): EOC") for v in found[1:])


def test_qp_tolerance_finding_flips_when_a_run_matches(tmp_path):
    ours, paper = read_table_csv(f"{FIG}/table1.csv"), read_table_csv("workflow/reference/paper_table1.csv")
    frame = pd.read_csv(f"{FIG}/work_precision.csv")
    runs = frame[(frame["N"] == 201) & (frame["tol_label"] != "exact") & frame["total_L4"].notna()]
    closest = (runs["total_L4"] / paper["1/201"]["L4"] - 1).abs().min()
    text = sm.qp_tolerance_finding(f"{FIG}/work_precision.csv", ours, paper, ())[0].text
    assert "is not reproduced" in text and f"of {len(runs)} runs" in text and f"+{100 * closest:.2f} %" in text
    frame.loc[runs.index[0], "total_L4"] = paper["1/201"]["L4"]
    frame.to_csv(tmp_path / "wp.csv", index=False)
    assert "is reproduced" in sm.qp_tolerance_finding(str(tmp_path / "wp.csv"), ours, paper, ())[0].text


def test_stability_counts():
    frame = pd.read_csv(f"{FIG}/stability.csv")
    text = sm.stability_findings(f"{FIG}/stability.csv", ())[0].text
    assert f"{len(frame)} runs" in text and f"{(frame['status'] == 'failed').sum()} failed" in text
    assert "never unexpected" in text


def test_the_mesh_study_headline_comes_from_its_table_and_follows_it(tmp_path):
    frame = pd.read_csv(f"{FIG}/meshes.csv")
    verdict = sm.meshes_findings(f"{FIG}/meshes.csv", ("m.csv",))[0]
    uniform = frame[frame["quasi_uniform"] & ~frame["reference"] & frame["norm"].str.endswith("_true")]
    same = int((uniform["vs_reference"] == "same").sum())
    assert f"{same} of {len(uniform)} true-norm orders are those of the paper's mesh" in verdict.text
    assert verdict.sources == ("m.csv",) and not verdict.text.endswith(".")
    matched = frame.assign(vs_reference="same")  # every family as the paper's mesh
    matched.to_csv(tmp_path / "meshes.csv", index=False)
    verdict = sm.meshes_findings(str(tmp_path / "meshes.csv"), ())[0]
    assert verdict.holds and verdict.text.startswith("On every quasi-uniform family")


def test_log_factor_fit_recovers_beta():
    N = np.array([101, 201, 401, 801, 1601])
    h = 1.0 / N
    beta, misfit = sm.log_factor_fit(N, 3.0 * h**1.5 * np.abs(np.log(h)) ** 0.3, 1.5)
    assert beta == pytest.approx(0.3) and misfit < 1e-12


def test_captions_pick_the_figures_paragraphs(tmp_path):
    rst = tmp_path / "theory.rst"
    rst.write_text("**Scene**: intro.\n\n``theory_rates``: the rates.\n\n``theory_extra``: more.\n", encoding="utf-8")
    assert sm.caption("theory_rates.png", rst) == "`theory_rates`: the rates."
    assert sm.caption("other.png", rst).startswith("**Scene**: intro.")


def test_missing_sources_are_named_with_the_target_that_writes_them(tmp_path, monkeypatch):
    from signorini.pipeline.paths import FIGURES

    monkeypatch.chdir(tmp_path)  # where no study has written anything
    sources = {"stability": FIGURES["stability_atlas"]["csv"], "theory": FIGURES["contact_set"]["csv"]}
    stability, contact = sm._missing(sources, ("stability", "theory"))
    assert stability.strength == "open" and "snakemake -c2 stability" in stability.text
    assert "snakemake -c2 theory" in contact.text and sm.target_of(FIGURES["summary"]["md"]) == "all"


def test_every_committed_finding_regenerates_from_the_committed_files():
    """Each bullet of the committed summary that rests on committed CSVs is what those CSVs give
    today, and the load rule's bullet quotes the reproduction report's table."""
    from signorini.pipeline.paths import FIGURES, REFERENCES

    committed = (ROOT / FIGURES["summary"]["md"]).read_text(encoding="utf-8")
    sources = {
        "table1_true": TRUE,
        "table1_fine": FINE,
        "contact_set": f"{FIG}/contact_set.csv",
        "work_precision": f"{FIG}/work_precision.csv",
        "stability": f"{FIG}/stability.csv",
    }
    cells = sm._true_cells(TRUE, FINE, FINEST)
    ours, paper = read_table_csv(f"{FIG}/table1.csv"), read_table_csv(REFERENCES["paper_table1"])
    found = [
        *sm.point_set_findings(cells, (TRUE, FINE)),
        *sm.l16_findings(cells, (TRUE, FINE)),
        *sm.rate_findings(cells, (TRUE, FINE, FINEST)),
        *sm.contact_findings(sources),
        *sm.race_findings(sources),
        *sm.stability_findings(sources["stability"], (sources["stability"],)),
        *sm.qp_tolerance_finding(
            sources["work_precision"], ours, paper, (sources["work_precision"], f"{FIG}/table1.csv")
        ),
    ]
    for bullet in sm._bullets(found):
        assert bullet in committed, bullet
    load = next(line for line in committed.splitlines() if "load vector by the norms' 16-point rule" in line)
    size = load.split("by at most ")[1].split(" relative")[0]
    table = (ROOT / FIGURES["reproduction"]["md"]).read_text(encoding="utf-8").split("## The load vector")[1]
    cells = [c for line in table.splitlines() if line.startswith("| 1/") for c in line.split("|")[2:-2]]
    cells_printed = [abs(float(c)) for c in cells if "±" not in c]  # "0 ± r": a change within round-off
    assert len(cells_printed) < len(cells)
    assert f"{max(cells_printed):.1e}" == size


def test_a_scene_off_the_papers_meshes_has_no_qp_finding():
    ours = {"1/11": {"L4": 1.0}}
    paper = read_table_csv("workflow/reference/paper_table1.csv")
    assert sm.qp_tolerance_finding(f"{FIG}/work_precision.csv", ours, paper, ()) == []


def test_true_tables_without_published_cells_give_no_point_set_finding(cells):
    other = cells.copy()
    other["paper"] = np.nan
    assert sm.point_set_findings(other, ()) == []


def test_the_figures_section_captions_every_committed_figure():
    """Every committed PNG has its entry and caption, whichever figures a run has drawn so far."""
    committed = {p.name for p in (ROOT / FIG).glob("*.png")}
    assert set(sm.FIGURE_CAPTIONS) == committed
    lines = sm.figures_section(ROOT / "workflow/report")
    assert sum(line.startswith("- [`") for line in lines) == len(committed)
    assert all(len(line) > 80 for line in lines if line.startswith("- [`"))  # a caption, not only a name
