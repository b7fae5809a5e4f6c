"""The page of the mesh-family study (``signorini.studies.meshes.report``) on made-up scenes: the
headline and each family's verdict say what the data say, and change when the data change."""

from __future__ import annotations

from signorini.studies.meshes.report import family_verdicts, findings, headline
from signorini.studies.verdict import Verdict


def test_the_headline_says_the_rates_belong_to_the_method_when_every_family_matches(study):
    scenes, table = study()
    verdict = headline(table, "ref")
    assert verdict.holds and verdict.strength == "measured"
    assert "On every quasi-uniform family (Delaunay (seed 0))" in verdict.text and "not of the" in verdict.text
    graded = "on the graded (grading 2) meshes (not quasi-uniform) the order against the unknowns changes: W1inf_true"
    assert graded in verdict.text and ": 0.50 → 1.01 (better)" in verdict.text


def test_the_headline_names_a_family_that_converges_slower(study):
    scenes, table = study({"L4_true": 2.0 - 0.3, "W1inf_true": 0.5, "H12": 1.5})
    verdict = headline(table, "ref")
    assert not verdict.holds and "(Delaunay (seed 0)) 1 of 2 true-norm orders are those of the paper's" in verdict.text
    assert "the others: L4_true on Delaunay (seed 0): 2.02 → 1.71 (worse)" in verdict.text


def test_each_family_verdict_lists_its_norms_by_outcome(study):
    scenes, table = study({"L4_true": 2.0 - 0.3, "W1inf_true": 0.5, "H12": 1.5})
    ref, dl, gr = family_verdicts(table, scenes, "ref")
    assert (
        ref.holds
        and "agrees for L4_true, W1inf_true, H12" in ref.text
        and "compared with the paper's mesh" not in ref.text
    )
    assert not dl.holds and "slower for L4_true" in dl.text and "worse for L4_true" in dl.text
    assert "order against the unknowns (not quasi-uniform)" in gr.text and "better for W1inf_true" in gr.text


def test_the_page_has_every_section_and_its_numbers(study):
    scenes, table = study()
    contact = {s.label: Verdict("Consistent with condition (A_h) on these meshes.", "measured") for s in scenes}
    page = findings(scenes, "ref", table, contact, "every value converged to 0.0001.")
    for heading in (
        "# Theorem 6.1 beyond",
        "## The meshes",
        "## Findings",
        "## Slopes against h",
        "## Orders against the unknowns",
        "## Errors and EOCs per mesh",
        "## The contact set",
        "## The true norms",
    ):
        assert heading in page
    assert "| Delaunay (seed 0) | `dl` | 50–400 |" in page and "L4_true ±0.030" in page
    assert page.count("(*measured*)") == 1 + 3 + 3


def test_the_headline_says_so_when_no_family_but_the_reference_is_quasi_uniform(study, scene):
    from signorini.studies.meshes.rates import rates_table

    scenes, _ = study()
    scenes = [scenes[0], scene("gr", "graded", {"grading": 2.0}, n_factor=5.5, ratio_growth=8.0)]
    verdict = headline(rates_table(scenes, "ref"), "ref")
    assert not verdict.holds and verdict.text.startswith("No family but the paper's is quasi-uniform")


def test_the_headline_reads_the_rates_table_alone_and_needs_true_norms(study):
    scenes, table = study()
    assert headline(table, "ref", ("a.csv",)).sources == ("a.csv",)
    plain = table[~table["norm"].str.endswith("_true")]
    verdict = headline(plain, "ref")
    assert not verdict.holds and verdict.text.startswith("The quasi-uniform families (Delaunay (seed 0)) have no true")


def test_the_tables_per_family_give_each_error_and_its_eoc(study):
    from signorini.studies.meshes.report import eoc_section

    scenes, _ = study()
    text = "\n".join(eoc_section(scenes[:1]))
    e = scenes[0].errors
    assert f"| 51 | {e['h'].iloc[0]:.3e} | 2,704 | {e['L4_true'].iloc[0]:.2e} |" in text
    assert f"| 101 | {e['h'].iloc[1]:.3e} | 10,404 | {e['L4_true'].iloc[1]:.2e} (2.00) |" in text
