"""The Snakemake workflow: config validation, the scene chain's stages, planning (`snakemake -n`),
artifacts, end to end on the built repository copy (``conftest.built_repo``)."""

from __future__ import annotations

import copy
import csv
import shutil

import numpy as np
import pytest
import yaml
from helpers import PROBLEM, ROOT, clone_built, copy_repo, planned, planned_rules, snakemake

from signorini.fem.mesh import mesh_width
from signorini.paper import PAPER_NORMS
from signorini.pipeline.artifacts import CorruptArtifactError, load_json, load_npz, save_json, save_npz
from signorini.pipeline.config import ConfigError, check_config
from signorini.pipeline.config import load_config as read_config
from signorini.pipeline.integrity import artifact_ok, quarantine_corrupt
from signorini.pipeline.joblog import job_log
from signorini.pipeline.paths import FIGURES, PATHS, TARGETS
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.eoc import eoc_stage
from signorini.studies.scene.errors import errors_stage
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh

NORMS = list(PAPER_NORMS)
SMOKE_N = [11, 21, 41]


def load_config() -> dict:
    return read_config(ROOT / "workflow/config.yaml")


# --- config and schema ---------------------------------------------------------------------


def validate(config: dict) -> None:
    """What the Snakefile does: schema validation, then the semantic checks."""
    from signorini.pipeline.config import validate_config

    validate_config(config, ROOT / "workflow/schemas/config.schema.yaml")
    check_config(config)


def test_shipped_config_is_valid():
    config = load_config()
    validate(config)
    assert config["scenes"]["paper"]["N"] == [101, 201, 301, 401, 501]
    assert config["scenes"]["paper"]["norms"] == NORMS
    assert config["scenes"]["paper"]["problem"] == {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}
    assert config["scenes"]["smoke"]["N"] == SMOKE_N


@pytest.mark.parametrize(
    ("path", "value", "expected"),
    [
        (("norms", 0), "L4x", ["norms", "L4x"]),  # unknown norm: schema pattern
        (("norms", 0), "L0.5", ["norms[0]", "p ≥ 1"]),  # passes the pattern, parse_norm rejects it
        (("solver",), "gurobi", ["solver", "gurobi"]),
        (("N", 0), 0, ["N[0]", "0", "≥ 1"]),
        (("N", 0), -3, ["N"]),
        (("N", 1), 201.5, ["N", "integer"]),
        (("N", 1), 201.0, ["N[1]", "not an integer"]),  # JSON schema counts 201.0 as integer
        (("N", 1), "201", ["N", "integer"]),
        (("N",), 101, ["N", "a list"]),
        (("norms",), "L4", ["norms", "a list"]),
        (("problem", "x0"), "half", ["x0", "number"]),
        (("problem", "R"), 0.6, ["problem", "R"]),  # support leaves the square: Problem rejects it
        (("nroms",), ["L4"], ["nroms"]),  # a typo in a key
    ],
)
def test_invalid_config_names_the_field(path, value, expected):
    config = copy.deepcopy(load_config())
    target = config["scenes"]["smoke"]
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    with pytest.raises(Exception) as info:  # WorkflowError (schema) or ConfigError (semantics)
        validate(config)
    message = str(info.value)
    for fragment in expected:
        assert fragment in message, message


def test_unknown_figures_scene_is_rejected():
    config = load_config()
    config["figures_scene"] = "nope"
    with pytest.raises(ConfigError, match="figures_scene"):
        validate(config)


def test_cli_rejects_bad_config_before_running(tmp_path):
    copy_repo(tmp_path)
    bad = {"scenes": {"smoke": {"norms": ["L4", "W17x"]}}}  # merged into the shipped config
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(bad))
    proc = snakemake(tmp_path, "-n", "--configfile", "bad.yaml", check=False)
    assert proc.returncode != 0
    assert "W17x" in proc.stderr + proc.stdout and "norms" in proc.stderr + proc.stdout
    assert not (tmp_path / "results").exists()


# --- stage functions and artifacts -----------------------------------------------------------


def solve_chain(d, N: int, npz="solution.npz", json="solution.json") -> None:
    """discretise + solve of the default problem on mesh N into directory d."""
    discretise_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / f"system{N}.npz", d / f"system{N}.json")
    solve_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / f"system{N}.npz", "active_set", d / npz, d / json)


def test_stage_chain_and_csv_contract(tmp_path):
    npz, sjson = tmp_path / "solution.npz", tmp_path / "solution.json"
    norm_jsons = {n: [] for n in ("L4", "W14")}
    for N in (8, 16):
        solve_chain(tmp_path, N)
        info = load_json(sjson)
        assert info["summary"]["certificate"]["ok"] and info["N"] == N
        assert set(load_npz(npz)) >= {"u", "lam", "active"}
        assert load_json(tmp_path / f"system{N}.json")["n_dofs"] == (N + 1) ** 2
        for n in norm_jsons:
            out = tmp_path / f"N{N}_{n}.json"
            norm_stage(SceneMesh(PROBLEM, N, "sw_ne"), npz, n, out, {})
            norm_jsons[n].append(out)
    errors_stage([8, 16], norm_jsons, tmp_path / "errors.csv")
    eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    rows = list(csv.DictReader((tmp_path / "errors.csv").open()))
    assert list(rows[0]) == ["N", "h", "L4", "W14"]
    assert [int(r["N"]) for r in rows] == [8, 16] and float(rows[1]["h"]) == mesh_width(16)
    eoc = list(csv.DictReader((tmp_path / "eoc.csv").open()))
    assert [r["N"] for r in eoc] == ["16", "regression"] and eoc[1]["h"] == ""
    assert float(eoc[0]["L4"]) == pytest.approx(float(eoc[1]["L4"]))  # two points: EOC = slope


def test_solve_refuses_the_system_of_another_mesh(tmp_path):
    discretise_stage(SceneMesh(PROBLEM, 8, "sw_ne"), tmp_path / "system.npz", tmp_path / "system.json")
    with pytest.raises(CorruptArtifactError, match="N=8, not N=9"):
        solve_stage(
            SceneMesh(PROBLEM, 9, "sw_ne"),
            tmp_path / "system.npz",
            "active_set",
            tmp_path / "s.npz",
            tmp_path / "s.json",
        )
    assert not (tmp_path / "s.npz").exists()


def test_norm_stage_refuses_corrupt_solution(tmp_path):
    npz = tmp_path / "solution.npz"
    solve_chain(tmp_path, 8)
    data = npz.read_bytes()
    npz.write_bytes(data[: len(data) // 2])
    with pytest.raises(CorruptArtifactError):
        norm_stage(SceneMesh(PROBLEM, 8, "sw_ne"), npz, "L4", tmp_path / "L4.json", {})
    assert not (tmp_path / "L4.json").exists()
    with pytest.raises(CorruptArtifactError, match="shape"):  # a solution of another mesh
        save_npz(npz, u=np.zeros(10))
        norm_stage(SceneMesh(PROBLEM, 8, "sw_ne"), npz, "L4", tmp_path / "L4.json", {})


def test_quarantine_moves_only_corrupt_artifacts(tmp_path):
    good, bad_json, bad_npz = tmp_path / "good.json", tmp_path / "bad.json", tmp_path / "bad.npz"
    save_json(good, {"value": 1.0})
    save_json(bad_json, {"value": 1.0})
    bad_json.write_text(bad_json.read_text()[:10])
    save_npz(bad_npz, u=np.arange(100.0))
    bad_npz.write_bytes(bad_npz.read_bytes()[:-40])
    moved = quarantine_corrupt([good, bad_json, bad_npz, tmp_path / "missing.npz"])
    assert sorted(moved) == sorted([str(bad_json), str(bad_npz)])
    assert good.exists() and not bad_json.exists() and not bad_npz.exists()
    assert (tmp_path / "bad.npz.corrupt").exists()


def test_failed_certificate_writes_nothing_and_logs_residuals(tmp_path, monkeypatch):
    import signorini.studies.scene.solve
    from signorini.solvers import Certificate, KKTError

    def failing(*args, **kwargs):
        raise KKTError("test solver", Certificate(1e-3, 0.0, 0.0, 0.0, 1e-10))

    monkeypatch.setattr(signorini.studies.scene.solve, "solve_discrete", failing)
    log = tmp_path / "solve.log"
    discretise_stage(SceneMesh(PROBLEM, 8, "sw_ne"), tmp_path / "system.npz", tmp_path / "system.json")
    with pytest.raises(KKTError), job_log(log):
        solve_stage(
            SceneMesh(PROBLEM, 8, "sw_ne"),
            tmp_path / "system.npz",
            "active_set",
            tmp_path / "s.npz",
            tmp_path / "s.json",
        )
    assert not (tmp_path / "s.npz").exists() and not (tmp_path / "s.json").exists()
    assert "stationarity=1.00e-03" in log.read_text()


def test_interrupted_write_leaves_no_file(tmp_path):
    from signorini.pipeline.artifacts import _atomic_write

    def killed(fh):
        fh.write(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _atomic_write(tmp_path / "x.npz", killed)
    assert list(tmp_path.iterdir()) == []


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
    assert "## Remarks on deviations" in repro
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
    snakemake(repo, "-c2", "all")
    outputs = [path for rule in TARGETS["all"] if rule != "runtime" for path in FIGURES[rule].values()]
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
    u_h moves by 1e-13 of its size, in three random patterns (the round-off of another processor;
    each value of Figure 2's fields by 1e-15 of itself), while the norms downstream really are
    recomputed from it."""
    repo = clone_built(built_repo, tmp_path / "repo")
    outputs = [path for rule in TARGETS["all"] if rule != "runtime" for path in FIGURES[rule].values()]
    reference = {path: (repo / path).read_bytes() for path in outputs}
    solutions = [repo / PATHS["solution_npz"].format(scene="smoke", N=N) for N in SMOKE_N]
    l4 = repo / PATHS["norm_json"].format(scene="smoke", N=SMOKE_N[-1], norm="L4")
    values = {load_json(l4)["value"]}
    rng = np.random.default_rng(20261201)
    for pattern in range(3):
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
    from conftest import BUILT_TARGETS

    proc = snakemake(built_repo, "-n", *BUILT_TARGETS)
    assert planned_rules(proc) == set(), proc.stdout


@pytest.mark.slow
def test_truncated_artifacts_are_detected_and_rebuilt(built_repo, tmp_path):
    repo = clone_built(built_repo, tmp_path / "repo")
    res = repo / "results/smoke"
    npz, njson, errors = res / "N11/solution.npz", res / "N21/norms/L4.json", res / "errors.csv"
    before_u, before_l4, before_errors = load_npz(npz)["u"], load_json(njson)["value"], errors.read_text()
    # truncated cache files (newer than their inputs, as after a damaged copy)
    npz.write_bytes(npz.read_bytes()[: npz.stat().st_size // 3])
    njson.write_text(njson.read_text()[:40])
    errors.write_text(before_errors[: len(before_errors) - 30])
    damaged = {path: path.read_bytes() for path in (npz, njson, errors)}
    # read-only calls name them and touch nothing
    for args in (["-n", "results/smoke/errors.csv"], ["--lint"], ["-l"], ["--summary"]):
        proc = snakemake(repo, *args, check=False)
        assert all(path.read_bytes() == data for path, data in damaged.items()), args
        assert not list(res.rglob("*.corrupt")), args
        if args[0] == "-n":
            assert all(str(path.relative_to(repo)) in proc.stderr for path in damaged), proc.stderr
    # a run moves them aside; errors.csv is rebuilt, and so is the norm it needs ...
    proc = snakemake(repo, "-c2", "results/smoke/errors.csv")
    for path in (npz, njson, errors):
        assert path.with_name(path.name + ".corrupt").exists()
    ran = planned(proc)
    assert ("norm", {"scene": "smoke", "N": "21", "norm": "L4"}) in ran and ("errors", {"scene": "smoke"}) in ran
    # ... while the N11 norms, computed from the sound solution, stay valid; the solution
    # is rebuilt (never read) as soon as a job needs it, e.g. a norm not computed yet
    assert not {"discretise", "solve"} & {rule for rule, _ in ran} and not npz.exists()
    new_norm = "results/smoke/N11/norms/L2.json"
    assert ("solve", {"scene": "smoke", "N": "11"}) in planned(snakemake(repo, "-n", new_norm))
    snakemake(repo, "-c2", "results/smoke/eoc.csv", new_norm)
    np.testing.assert_allclose(load_npz(npz)["u"], before_u, rtol=0, atol=1e-14)
    assert load_json(njson)["value"] == pytest.approx(before_l4, rel=1e-12)
    assert load_json(res / "N11/norms/L2.json")["value"] > 0
    rebuilt = list(csv.DictReader(errors.open()))
    assert [r["N"] for r in rebuilt] == ["11", "21", "41"]
    for old, new in zip(csv.DictReader(before_errors.splitlines()), rebuilt, strict=True):
        assert float(new["L4"]) == pytest.approx(float(old["L4"]), rel=1e-12)


def test_csv_check_detects_truncation(tmp_path):
    good = "N,h,L4\n11,0.09,0.04\n21,0.047,0.01\n"
    (tmp_path / "errors.csv").write_text(good)
    assert artifact_ok(tmp_path / "errors.csv")
    for bad in (good[:-1], good[:-8], "N,h,L4\n11,0.09,\n"):
        (tmp_path / "errors.csv").write_text(bad)
        assert not artifact_ok(tmp_path / "errors.csv"), bad
    (tmp_path / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\nregression,,1.9\n")
    assert artifact_ok(tmp_path / "eoc.csv")
    (tmp_path / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\n")
    assert not artifact_ok(tmp_path / "eoc.csv")


PER_MESH = ("--config", "norm_jobs=per_mesh")


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
