"""The studies beyond the paper end to end: the theory scene's, the stability atlas's, the
work-precision study's and the true norms' outputs of the built repository copy
(``conftest.built_repo``)."""

from __future__ import annotations

import csv
import math

import pandas as pd
from helpers import snakemake

from signorini.fem.norms.names import true_name
from signorini.fem.norms.true import RTOL
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


def test_meshes_target_end_to_end(built_repo):
    """The small mesh-family study of the built copy: a mesh job per N of a family scene only, its
    artifact read by the later stages (meshio reads its .vtu), the page with every section and a
    verdict per family, the rates table's verdicts, a figure."""
    import meshio

    from signorini.pipeline.artifacts import load_json
    from signorini.studies.scene.store import read_errors_csv

    out = built_repo / "paper_figures"
    md = (out / "meshes.md").read_text(encoding="utf-8")
    for heading in ("## The meshes", "## Findings", "## Slopes against h", "## Orders against the unknowns",
                    "## The contact set and condition (A_h)", "## The true norms' accuracy"):
        assert heading in md, heading
    assert md.count("(*measured*)") >= 1 + 4 + 4  # the headline, a verdict per family, (A_h) per family
    rates = pd.read_csv(out / "meshes.csv")
    assert set(rates["scene"]) == {"meshes_fk", "meshes_delaunay", "meshes_delaunay_seed1", "meshes_graded"}
    assert set(rates["vs_expected"]) <= {"agrees", "faster", "slower"}
    assert (rates.loc[rates["scene"] == "meshes_fk", "vs_reference"] == "same").all()
    assert (out / "meshes_rates.png").stat().st_size > 10_000
    assert not (built_repo / "results/meshes_fk/N9/mesh.npz").exists()  # the paper's mesh: no mesh job
    info = load_json(built_repo / "results/meshes_graded/N16/mesh.json")
    assert info["family"] == "graded" and info["n_vertices"] > 17**2
    vtu = meshio.read(built_repo / "results/meshes_delaunay/N33/mesh.vtu")
    assert len(vtu.points) == load_json(built_repo / "results/meshes_delaunay/N33/mesh.json")["n_vertices"]
    errors = read_errors_csv(built_repo / "results/meshes_delaunay/errors.csv")
    assert errors["h"].iloc[-1] == info_h(built_repo, "meshes_delaunay", 33)


def info_h(repo, scene: str, N: int) -> float:
    """The ``h`` a family mesh's artifact records: its longest edge."""
    from signorini.pipeline.artifacts import load_json

    return load_json(repo / f"results/{scene}/N{N}/mesh.json")["h"]


def test_small_study_end_to_end(built_repo):
    """The small study of the built copy (N = 11, 21 of the smoke scene; active set and OSQP at two
    tolerances): the paper_figures outputs, the source scene's systems and solutions reused (not
    recomputed), a no-op rerun."""
    out = built_repo / "paper_figures"
    for name in ("work_precision.pdf", "work_precision.png", "cost_of_accuracy.pdf", "cost_of_accuracy.png"):
        assert (out / name).stat().st_size > 1000, name
    df = pd.read_csv(out / "work_precision.csv")
    df = df[~df["solver"].str.startswith("petsc_")]  # the peer: tests/test_peers.py
    assert len(df) == 2 * (2 + 3)  # per N: the active set (cascade, cold), OSQP at its default and two tolerances
    assert set(df["config"]) == {"active_set", "active_set_cold", "osqp"}
    assert (df["time_runs"] >= 1).all() and (df["time_ref"] > 0).all() and (df["ref_s"] > 0).all()
    assert set(df.loc[df["config"] == "active_set_cold", "start"]) == {"cold"}
    exact = df[df["config"] == "active_set"]
    assert (exact["alg_L4"] == 0).all() and (exact["total_L4"] == exact["disc_L4"]).all()
    assert set(df["status"]) <= {"ok", "inaccurate"}
    assert {c.split("_", 1)[1] for c in df.columns if c.startswith("alg_")} == {"L4", "W14"}
    md = (out / "work_precision.md").read_text()
    assert "## Which tolerance keeps Table 1" in md and "Machine load during the measurements" in md
    assert "**Timing protocol**" in md and "| cold against cold: ours | its time |" in md
    assert "| active set (cold) |" in md  # ours from the cold start, named per mesh
    # reused: the smoke scene's systems and solutions, none of the study scene's own
    assert (built_repo / "results/smoke/N21/solution.npz").exists()
    assert not list((built_repo / "results/work_precision").glob("N*/s*.npz"))
    assert (df["build_s"] > 0).all()  # the assembly time of the smoke scene's discretise job
    noop = snakemake(built_repo, "-n", "work_precision")
    assert "Nothing to be done" in noop.stdout + noop.stderr
    assert math.isfinite(df["time_s"].min())


def test_true_norm_artifacts_of_the_second_case_carry_their_accuracy(built_repo):
    from signorini.pipeline.artifacts import load_json

    for name in ("L4_true", "Linf_true", "W14_true", "W1inf_true", "H12_true"):
        art = load_json(built_repo / f"results/case2/N241/norms/{name}.json")
        acc = art["quadrature_error"]
        assert acc["converged"] and acc["rtol"] == RTOL and len(acc["levels"]) >= 2
        assert acc["error_estimate"] <= RTOL * art["value"]
        assert acc["levels"][-1]["value"] == art["value"]


def test_true_norms_target_renders_every_norm_of_table_2(built_repo):
    """The test workflow renders the smoke scene (N = 11, 21, 41): a row per mesh and norm, converged."""
    import pandas as pd

    from signorini.published import TABLE2_NORMS

    t1 = pd.read_csv(built_repo / "paper_figures/table1_true.csv")
    assert list(t1["norm"]) == list(TABLE2_NORMS) * 3 and list(t1["h"].unique()) == ["1/11", "1/21", "1/41"]
    assert (t1["quadrature_error"] <= RTOL * t1["true"]).all()
    assert t1["paper"].isna().all()  # the paper has no row for these meshes
    t2 = pd.read_csv(built_repo / "paper_figures/table2_true.csv")
    assert list(t2.columns) == ["h", *(true_name(n) for n in TABLE2_NORMS)]
    assert "## Gap per norm" in (built_repo / "paper_figures/table1_true.md").read_text()


def test_fine_target_continues_table_2_on_its_own_scene(built_repo):
    """`fine` renders the scene fine's meshes (N = 9, 17 in the test workflow), not the paper's,
    and names its own command and errors table."""
    import pandas as pd

    from signorini.published import TABLE2_NORMS

    t1 = pd.read_csv(built_repo / "paper_figures/table1_fine.csv")
    assert list(t1["norm"]) == list(TABLE2_NORMS) * 2 and list(t1["h"].unique()) == ["1/9", "1/17"]
    assert (t1["quadrature_error"] <= RTOL * t1["true"]).all()
    t2 = pd.read_csv(built_repo / "paper_figures/table2_fine.csv")
    assert list(t2.columns) == ["h", *(true_name(n) for n in TABLE2_NORMS)]
    assert list(t2["h"]) == ["1/17", "regr.", "theo."]
    md = (built_repo / "paper_figures/table2_fine.md").read_text()
    assert "snakemake -c2 fine" in md and "`table1_fine.md`" in md and "true_norms" not in md
