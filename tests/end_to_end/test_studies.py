"""The studies beyond the paper end to end: the theory scene's and the stability atlas's outputs of
the built repository copy (``conftest.built_repo``)."""

from __future__ import annotations

import csv

from signorini.studies.stability import atlas as stab_atlas


def test_small_atlas_end_to_end(built_repo):
    from helpers import TEST_SCENES, snakemake

    out = built_repo / "paper_figures"
    rows = list(csv.DictReader((out / "stability.csv").open()))
    cases = TEST_SCENES["stability"]["atlas"]["cases"]
    expected = sum(len(c.get("solvers", ["active_set", "osqp", "osqp_raw"])) for c in cases)
    assert len(rows) == expected
    assert {r["status"] for r in rows} <= set(stab_atlas.STATUSES)
    assert not any(r["nan_inf"] == "True" for r in rows)
    exact = {r["case"]: r for r in rows if r["solver"] == "active_set"}
    assert all(r["as_expected"] == "True" for r in exact.values())
    assert exact["bad_spd"]["status"] == "failed" and exact["bad_spd"]["reason"].startswith("BadInputError")
    assert float(exact["A_1e-9"]["ref_diff_u"]) <= 1e-10 and exact["A_1e-9"]["ref_same_contact"] == "True"
    assert float(exact["f_zero"]["err_L4"]) == 0.0
    normalized = next(r for r in rows if r["case"] == "A_1e-9" and r["solver"] == "osqp")
    assert normalized["status"] == "ok" and float(normalized["ref_diff_u"]) <= 1e-8
    md = (out / "stability.md").read_text()
    assert all(f"**{c['name']}**" in md for c in cases)
    assert sum(line.startswith("- **") for line in md.splitlines()) == len(cases)  # one line per case
    for ext in ("pdf", "png"):
        assert (out / f"stability.{ext}").stat().st_size > 10_000
    # a rerun is a no-op; the scene is not part of `all`
    proc = snakemake(built_repo, "-n", "stability")
    assert "Nothing to be done" in proc.stdout + proc.stderr
    proc = snakemake(built_repo, "-n", "--forceall", "all")
    assert "stability_case" not in proc.stdout + proc.stderr


def test_theory_target_end_to_end(built_repo):
    md = (built_repo / "paper_figures/theory.md").read_text()
    assert "Supercloseness" in md and "| L4 |" in md
    # the test scene's true norms: their own EOC table, kept out of the rates against p
    true_section = md.split("## The same EOCs of the true norms")[1].split("##")[0]
    assert "| h | L4_true | W1inf_true |" in true_section and "| expected (− ε) | 2.000 | 0.500 |" in true_section
    assert "| L4_true |" not in md.split("## Rates against p")[1]
    for name in ("theory_rates.png", "theory_extra.png", "theory.csv"):
        assert (built_repo / "paper_figures" / name).stat().st_size > 0
