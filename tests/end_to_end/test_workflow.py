"""The Snakemake workflow on repository copies: a bad config refused by Snakemake, what a dry run
plans, norm jobs per mesh, and the outputs of the built repository copy (``conftest.built_repo``):
the smoke scene's tables, the paper's outputs, byte-identical reruns, the second manufactured
case's EOCs and the vtk rule."""

from __future__ import annotations

import csv
import shutil

import numpy as np
import pytest
import yaml
from helpers import NORMS, PROBLEM, ROOT, SMOKE_N, clone_built, copy_repo, planned, planned_rules, read_vtu, snakemake

from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem
from signorini.pipeline.artifacts import load_json, load_npz, save_npz
from signorini.pipeline.config import load_config
from signorini.pipeline.config import load_config as read_config
from signorini.pipeline.paths import FIGURES, PATHS, TARGETS


def test_cli_rejects_bad_config_before_running(tmp_path):
    copy_repo(tmp_path)
    bad = {"scenes": {"smoke": {"norms": ["L4", "W17x"]}}}  # merged into the shipped config
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(bad))
    proc = snakemake(tmp_path, "-n", "--configfile", "bad.yaml", check=False)
    assert proc.returncode != 0
    assert "W17x" in proc.stderr + proc.stdout and "norms" in proc.stderr + proc.stdout
    assert not (tmp_path / "results").exists()


# --- the workflow on the smoke scene ---------------------------------------------------------


def test_figure3_plans_only_l4_and_w14(tmp_path):
    copy_repo(tmp_path)
    proc = snakemake(tmp_path, "-n", "paper_figures/figure3.pdf")
    jobs = planned(proc)
    norms = {wc["norm"] for rule, wc in jobs if rule == "norm"}
    assert norms == {"L4", "W14"}
    assert sorted(int(wc["N"]) for rule, wc in jobs if rule == "solve") == [101, 201, 301, 401, 501]
    assert {rule for rule, _ in jobs} == {"discretise", "solve", "norm", "figure3"}


def test_scene_added_with_configfile_plans_its_norms_only(tmp_path):
    copy_repo(tmp_path)
    mine = {"scenes": {"mine": {"N": [8, 16], "norms": ["L2", "H1"], "solver": "active_set", "problem": PROBLEM}}}
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mine))
    jobs = planned(snakemake(tmp_path, "-n", "results/mine/eoc.csv", "--configfile", "mine.yaml"))
    assert sorted((wc["N"], wc["norm"]) for rule, wc in jobs if rule == "norm") == [
        ("16", "H1"),
        ("16", "L2"),
        ("8", "H1"),
        ("8", "L2"),
    ]
    assert {rule for rule, _ in jobs} == {"discretise", "solve", "norm", "errors", "eoc"}


@pytest.mark.slow
def test_smoke_csv_contract(built_repo):
    rows = list(csv.DictReader((built_repo / "results/smoke/errors.csv").open()))
    assert list(rows[0]) == ["N", "h", *NORMS]
    assert [int(r["N"]) for r in rows] == SMOKE_N
    for r in rows:
        assert float(r["h"]) == pytest.approx(1.0 / int(r["N"]), rel=1e-15)
        assert all(float(r[n]) > 0 for n in NORMS)
    eoc = list(csv.DictReader((built_repo / "results/smoke/eoc.csv").open()))
    assert list(eoc[0]) == ["N", "h", *NORMS]
    assert [r["N"] for r in eoc] == ["21", "41", "regression"]
    assert eoc[-1]["h"] == ""
    assert 1.5 < float(eoc[-1]["L4"]) < 2.5 and 0.7 < float(eoc[-1]["W14"]) < 1.3
    # a scene of two norms computes exactly its two norms
    mine = list(csv.DictReader((built_repo / "results/mine/errors.csv").open()))
    assert list(mine[0]) == ["N", "h", "L2", "H1"] and [int(r["N"]) for r in mine] == [8, 16]
    assert sorted(p.name for p in (built_repo / "results/mine/N8/norms").iterdir()) == ["H1.json", "L2.json"]


@pytest.mark.slow
def test_smoke_render_outputs(built_repo):
    figs = built_repo / "paper_figures"
    for name in ("table1.csv", "table1.md", "table1.tex", "table2.csv", "table2.md", "table2.tex"):
        assert (figs / name).stat().st_size > 0
    for name in ("figure2.pdf", "figure2.png", "figure3.pdf", "figure3.png"):
        assert (figs / name).read_bytes()[:4] in (b"%PDF", b"\x89PNG")
    t2 = (figs / "table2.csv").read_text().splitlines()
    assert t2[0] == "h,L4,L16,Linf,W14,W116,W1inf,H12" and t2[-2].startswith("regr.") and t2[-1].startswith("theo.")
    repro = (figs / "reproduction.md").read_text()
    assert "## The conventions" in repro and "## What reproduces and what does not" in repro
    assert (built_repo / "workflow/reference/deviation_remarks.md").read_text().strip() in repro
    runtime = list(csv.DictReader((figs / "runtime.csv").open()))
    assert [r["rule"] for r in runtime[:3]] == ["discretise", "solve", "norm"] and len(runtime) == 3 * (2 + 7)
    assert all(float(r["benchmark_wall_s"]) > 0 for r in runtime)


@pytest.mark.slow
def test_a_second_cold_run_gives_the_same_bytes(built_repo, tmp_path):
    """Everything `all` writes, but the run times, is byte-identical between two runs from empty
    caches (single-threaded BLAS; PDF/PNG without dates): a reproduction leaves `git status` clean."""
    repo = copy_repo(tmp_path)
    shutil.copy2(built_repo / "workflow/config.yaml", repo / "workflow/config.yaml")
    outputs = [path for rule in TARGETS["all"] if rule != "runtime" for path in FIGURES[rule].values()]
    # the other studies' outputs, which a clone holds committed and the summary reads
    (repo / "paper_figures").mkdir()
    for path in (built_repo / "paper_figures").iterdir():
        if f"paper_figures/{path.name}" not in outputs:
            shutil.copy2(path, repo / "paper_figures" / path.name)
    snakemake(repo, "-c2", "all")
    outputs += [PATHS["errors_csv"].format(scene="smoke"), PATHS["eoc_csv"].format(scene="smoke")]
    for path in outputs:
        assert (repo / path).read_bytes() == (built_repo / path).read_bytes(), path
    ignored = (ROOT / ".gitignore").read_text().splitlines()
    assert FIGURES["runtime"]["csv"] in ignored  # the one output that changes per run is not committed


def _perturb_npz(path, keys, relative, rng, normwise=True) -> dict:
    """Move the arrays ``keys`` of an archive by ``relative · max |a|`` (``normwise``) or by ``relative · |a|``
    times uniform noise, rewritten with a valid checksum (as another processor's round-off would
    leave them); the new arrays."""
    arrays = load_npz(path)
    for key in keys:
        a = arrays[key]
        scale = np.abs(a).max() if normwise else np.abs(a)
        arrays[key] = a + relative * scale * rng.uniform(-1.0, 1.0, a.shape)
    save_npz(path, **arrays)
    return arrays


@pytest.mark.slow
def test_round_off_in_the_solutions_changes_no_committed_output(built_repo, tmp_path):
    """Every file `all` writes under paper_figures/ (but the run times) keeps its bytes when each
    u_h moves by 1e-13 of its size, in two random patterns (the round-off of another processor;
    each value of Figure 2's fields by 1e-15 of itself), while the norms downstream really are
    recomputed from it."""
    repo = clone_built(built_repo, tmp_path / "repo")
    outputs = [path for rule in TARGETS["all"] if rule != "runtime" for path in FIGURES[rule].values()]
    reference = {path: (repo / path).read_bytes() for path in outputs}
    solutions = [repo / PATHS["solution_npz"].format(scene="smoke", N=N) for N in SMOKE_N]
    l4 = repo / PATHS["norm_json"].format(scene="smoke", N=SMOKE_N[-1], norm="L4")
    values = {load_json(l4)["value"]}
    rng = np.random.default_rng(20261201)
    for pattern in range(2):
        perturbed = [_perturb_npz(path, ["u"], 1e-13, rng)["u"] for path in solutions]
        # u and f are exact functions: a libm's last bits, where u = 0 outside its support exactly
        _perturb_npz(repo / PATHS["fields_npz"].format(scene="smoke"), ["u", "f"], 1e-15, rng, normwise=False)
        snakemake(repo, "-c2", "all")
        for path, u in zip(solutions, perturbed, strict=True):  # the perturbed u_h was used, not re-solved
            assert np.array_equal(load_npz(path)["u"], u), path
        values.add(load_json(l4)["value"])
        assert len(values) == pattern + 2, "the norms were not recomputed from the perturbed u_h"
        for path in outputs:
            assert (repo / path).read_bytes() == reference[path], f"pattern {pattern}: {path} changed"


@pytest.mark.slow
def test_up_to_date_workflow_plans_nothing(built_repo):
    from helpers import BUILT_TARGETS

    proc = snakemake(built_repo, "-n", *BUILT_TARGETS)
    assert planned_rules(proc) == set(), proc.stdout


PER_MESH = ("--config", "norm_jobs=per_mesh")


def test_a_scenes_own_per_mesh_norm_jobs_batch_its_convention_norms_only(tmp_path):
    """A scene's ``norm_jobs: per_mesh`` (the theory scene's) overrides the config's per_norm: one
    ``norms_<scene>`` job per mesh for its norms under the conventions, a job per true norm;
    the other scenes keep a job per norm."""
    copy_repo(tmp_path)
    mine = {"scenes": {"mine": {"N": [8, 16], "norms": ["L2", "W14", "L4_true"], "norm_jobs": "per_mesh"}}}
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mine))
    targets = ["results/mine/errors.csv", "results/smoke/errors.csv"]
    jobs = planned(snakemake(tmp_path, "-n", "--configfile", "mine.yaml", "--", *targets))
    norm_jobs = sorted(
        (rule, wc.get("scene", ""), wc["N"], wc.get("norm", "")) for rule, wc in jobs if rule.startswith("norm")
    )
    smoke = read_config(tmp_path / "workflow/config.yaml")["scenes"]["smoke"]
    assert norm_jobs == sorted(
        [("norms_mine", "", N, "") for N in ("8", "16")]  # the scene is in the rule's name
        + [("norm", "mine", N, "L4_true") for N in ("8", "16")]
        + [("norm", "smoke", str(N), n) for N in SMOKE_N for n in smoke["norms"]]
    )


def test_per_mesh_norm_jobs_compute_the_same_norms_and_switching_reruns_nothing(built_repo, tmp_path):
    """``norm_jobs: per_mesh`` (the slurm profile): one job per mesh computes all of the scene's
    norms, to the same bits as one job per norm; artifacts of either mode satisfy the other; a norm
    outside the scene's list stays a job of its own; runtime.csv has one row per mesh for them."""
    repo = clone_built(built_repo, tmp_path / "repo")
    target = "results/smoke/errors.csv"
    assert planned(snakemake(repo, "-n", *PER_MESH, "--", target)) == []  # per_norm artifacts serve
    norms = read_config(repo / "workflow/config.yaml")["scenes"]["smoke"]["norms"]
    Ns = [11, 21, 41]
    before = {(N, n): load_json(repo / f"results/smoke/N{N}/norms/{n}.json") for N in Ns for n in norms}
    errors_before = (repo / target).read_bytes()
    for path in (repo / "results/smoke").glob("N*/norms/*.json"):
        path.unlink()
    proc = snakemake(repo, "-c2", *PER_MESH, "--", target, "paper_figures/runtime.csv")
    ran = [(rule, wc.get("N")) for rule, wc in planned(proc) if rule.startswith("norm")]
    assert sorted(ran) == [("norms_smoke", str(N)) for N in Ns]
    for (N, n), old in before.items():
        new = load_json(repo / f"results/smoke/N{N}/norms/{n}.json")
        assert new["value"] == old["value"], (N, n)
        assert new["timings"]["mesh_shared_by"] == norms
    assert (repo / target).read_bytes() == errors_before
    rows = list(csv.DictReader((repo / "paper_figures/runtime.csv").open()))
    assert [(r["rule"], r["N"]) for r in rows if r["rule"].startswith("norm")] == [("norms", str(N)) for N in Ns]
    assert all(r["norm"] == " ".join(norms) and float(r["timer_s"]) > 0 for r in rows if r["rule"] == "norms")
    assert planned(snakemake(repo, "-n", "--", target)) == []  # and back: per_mesh artifacts serve
    extra = "results/smoke/N21/norms/L8.json"  # not in the scene's list: one job of its own
    only = planned(snakemake(repo, "-n", *PER_MESH, "--", extra))
    assert only == [("norm", {"scene": "smoke", "N": "21", "norm": "L8"})]


@pytest.mark.slow
def test_vtk_rule_writes_a_scene_solution(built_repo, tmp_path):
    repo = clone_built(built_repo, tmp_path / "repo")
    target = "results/smoke/N21/solution.vtu"
    assert [rule for rule, _ in planned(snakemake(repo, "-n", target))] == ["vtk"]  # from the cached solution
    snakemake(repo, "-c1", target)
    data = read_vtu(repo / target)
    solution = load_npz(repo / "results/smoke/N21/solution.npz")
    np.testing.assert_array_equal(data["u_h"], solution["u"])
    mesh = friedrichs_keller(21)
    np.testing.assert_array_equal(data["lambda"][boundary_nodes(mesh)], solution["lam"])


# The second manufactured case of the shipped config (scene ``case2``: x0 = 0.55, R = 0.4, A = 5, the
# free point at 0.55 of a cell on every mesh): EOCs of its three finest meshes (h = 1/161, 1/201,
# 1/241) against the theory, for the paper's conventions and the true norms alike.  The tolerance
# is 0.03 (0.05 for H^{1/2}, whose EOCs approach 3/2 from below: 1.47 in the paper's case too).
# L^∞ is asymptotic from h = 1/161 on (EOC 2 before: the smooth part of the error dominates).
CASE2_THEORY = {"L4": (2.0, 0.03), "Linf": (1.5, 0.03), "W14": (1.0, 0.03), "W1inf": (0.5, 0.03), "H12": (1.5, 0.05)}


def test_second_case_eocs_on_its_finest_meshes_match_the_theory(built_repo):
    import pandas as pd

    shipped = ROOT / "workflow/config.yaml"
    config = load_config(shipped)["scenes"]["case2"]
    problem = Problem.from_params(config["problem"])
    assert all(0.0 < (problem.x0 * N) % 1.0 < 1.0 for N in config["N"])  # never a mesh node
    eocs = pd.read_csv(built_repo / "results/case2/eoc.csv", dtype={"N": str})
    finest = eocs[eocs["N"] != "regression"].tail(3)
    assert list(finest["N"]) == [str(N) for N in config["N"][-3:]]
    for norm, (rate, tol) in CASE2_THEORY.items():
        for name in (norm, norm + "_true"):
            assert np.all(np.abs(finest[name].to_numpy() - rate) <= tol), (name, finest[name].tolist())
