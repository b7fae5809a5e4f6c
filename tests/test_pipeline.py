"""The Snakemake workflow: config validation, planning (`snakemake -n`), artifacts, end to end.

Workflow runs happen in a temporary copy of the repository (Snakefile, workflow/, src/), so
the real tree and its results/ cache are never touched.  The `smoke` scene is run once per
session (module fixture) and the later tests plan or rebuild on top of it.
"""

from __future__ import annotations

import copy
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from signorini import pipeline
from signorini.artifacts import CorruptArtifactError, load_json, load_npz, save_json, save_npz
from signorini.mesh import mesh_width

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
NORMS = ["L4", "L16", "Linf", "W14", "W116", "W1inf", "H12"]
SMOKE_N = [11, 21, 41]


def load_config() -> dict:
    return yaml.safe_load((ROOT / "workflow/config.yaml").read_text())


def copy_repo(dest: Path) -> Path:
    """Snakefile, workflow/ and src/ (the rules' code inputs) into ``dest``; mtimes preserved."""
    shutil.copy2(ROOT / "Snakefile", dest / "Snakefile")
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc")
    shutil.copytree(ROOT / "workflow", dest / "workflow", ignore=ignore)
    shutil.copytree(ROOT / "src", dest / "src", ignore=ignore)
    return dest


def snakemake(workdir: Path, *args: str, check: bool = True, timeout: float = 300) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [SNAKEMAKE, *args],
        cwd=workdir,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-6000:]}")
    return proc


def planned(proc: subprocess.CompletedProcess) -> list[tuple[str, dict[str, str]]]:
    """(rule, wildcards) of every job a dry run plans."""
    jobs: list[tuple[str, dict[str, str]]] = []
    for line in (proc.stdout + proc.stderr).splitlines():
        if m := re.match(r"^(?:local)?rule (\w+):$", line):
            jobs.append((m.group(1), {}))
        elif (m := re.match(r"^\s+wildcards: (.*)$", line)) and jobs:
            jobs[-1][1].update(kv.split("=", 1) for kv in m.group(1).split(", "))
    return jobs


def planned_rules(proc: subprocess.CompletedProcess) -> set[str]:
    return {rule for rule, _ in planned(proc)} - {"all"}


# --- config and schema ---------------------------------------------------------------------


def validate(config: dict) -> None:
    """What the Snakefile does: schema validation, then the semantic checks."""
    from snakemake.utils import validate as smk_validate

    smk_validate(config, str(ROOT / "workflow/schemas/config.schema.yaml"))
    pipeline.check_config(config)


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
        (("N", 0), 0, ["N", "minimum"]),
        (("N", 0), -3, ["N"]),
        (("N", 1), 201.5, ["N", "integer"]),
        (("N", 1), 201.0, ["N[1]", "not an integer"]),  # JSON schema counts 201.0 as integer
        (("N", 1), "201", ["N", "integer"]),
        (("N",), 101, ["N", "array"]),
        (("norms",), "L4", ["norms", "array"]),
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
    with pytest.raises(pipeline.ConfigError, match="figures_scene"):
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


PROBLEM = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}


def test_stage_chain_and_csv_contract(tmp_path):
    npz, sjson = tmp_path / "solution.npz", tmp_path / "solution.json"
    norm_jsons = {n: [] for n in ("L4", "W14")}
    for N in (8, 16):
        pipeline.solve_stage(PROBLEM, N, "active_set", npz, sjson)
        info = load_json(sjson)
        assert info["summary"]["certificate"]["ok"] and info["N"] == N
        assert set(load_npz(npz)) >= {"u", "lam", "active"}
        for n in norm_jsons:
            out = tmp_path / f"N{N}_{n}.json"
            pipeline.norm_stage(PROBLEM, N, npz, n, out)
            norm_jsons[n].append(out)
    pipeline.collect_errors([8, 16], norm_jsons, tmp_path / "errors.csv")
    pipeline.eoc_table(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    rows = list(csv.DictReader((tmp_path / "errors.csv").open()))
    assert list(rows[0]) == ["N", "h", "L4", "W14"]
    assert [int(r["N"]) for r in rows] == [8, 16] and float(rows[1]["h"]) == mesh_width(16)
    eoc = list(csv.DictReader((tmp_path / "eoc.csv").open()))
    assert [r["N"] for r in eoc] == ["16", "regression"] and eoc[1]["h"] == ""
    assert float(eoc[0]["L4"]) == pytest.approx(float(eoc[1]["L4"]))  # two points: EOC = slope


def test_norm_stage_refuses_corrupt_solution(tmp_path):
    npz = tmp_path / "solution.npz"
    pipeline.solve_stage(PROBLEM, 8, "active_set", npz, tmp_path / "solution.json")
    data = npz.read_bytes()
    npz.write_bytes(data[: len(data) // 2])
    with pytest.raises(CorruptArtifactError):
        pipeline.norm_stage(PROBLEM, 8, npz, "L4", tmp_path / "L4.json")
    assert not (tmp_path / "L4.json").exists()
    with pytest.raises(CorruptArtifactError, match="shape"):  # a solution of another mesh
        save_npz(npz, u=np.zeros(10))
        pipeline.norm_stage(PROBLEM, 8, npz, "L4", tmp_path / "L4.json")


def test_quarantine_moves_only_corrupt_artifacts(tmp_path):
    good, bad_json, bad_npz = tmp_path / "good.json", tmp_path / "bad.json", tmp_path / "bad.npz"
    save_json(good, {"value": 1.0})
    save_json(bad_json, {"value": 1.0})
    bad_json.write_text(bad_json.read_text()[:10])
    save_npz(bad_npz, u=np.arange(100.0))
    bad_npz.write_bytes(bad_npz.read_bytes()[:-40])
    moved = pipeline.quarantine_corrupt([good, bad_json, bad_npz, tmp_path / "missing.npz"])
    assert sorted(moved) == sorted([str(bad_json), str(bad_npz)])
    assert good.exists() and not bad_json.exists() and not bad_npz.exists()
    assert (tmp_path / "bad.npz.corrupt").exists()


def test_failed_certificate_writes_nothing_and_logs_residuals(tmp_path, monkeypatch):
    import signorini.discrete
    from signorini.solvers import Certificate, KKTError

    def failing(*args, **kwargs):
        raise KKTError("test solver", Certificate(1e-3, 0.0, 0.0, 0.0, 1e-10))

    monkeypatch.setattr(signorini.discrete, "solve_discrete", failing)
    log = tmp_path / "solve.log"
    with pytest.raises(KKTError), pipeline.job_log(log):
        pipeline.solve_stage(PROBLEM, 8, "active_set", tmp_path / "s.npz", tmp_path / "s.json")
    assert not (tmp_path / "s.npz").exists() and not (tmp_path / "s.json").exists()
    assert "stationarity=1.00e-03" in log.read_text()


def test_interrupted_write_leaves_no_file(tmp_path):
    from signorini.artifacts import _atomic_write

    def killed(fh):
        fh.write(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _atomic_write(tmp_path / "x.npz", killed)
    assert list(tmp_path.iterdir()) == []


def test_stage_modules_cover_what_stages_import(tmp_path):
    """Each rule lists the package modules its stage runs: run every stage in a fresh
    interpreter and compare the imported signorini modules with STAGE_MODULES."""
    script = f"""
import json, sys
import numpy as np
from signorini import pipeline
from signorini.artifacts import load_npz
stage, d = sys.argv[1], {str(tmp_path)!r}
P = {PROBLEM!r}
if stage == "solve":
    pipeline.solve_stage(P, 8, "active_set", d + "/s.npz", d + "/s.json")
elif stage == "norm":
    pipeline.norm_stage(P, 8, d + "/s.npz", "W1inf", d + "/n.json")
elif stage == "sample":
    pipeline.sample_stage(P, 11, d + "/f.npz")
elif stage == "errors":
    pipeline.collect_errors([8], {{"W1inf": [d + "/n.json"]}}, d + "/errors.csv")
elif stage == "eoc":
    pipeline.eoc_table(d + "/errors.csv", d + "/eoc.csv")
elif stage == "tables":
    from signorini import tables
    e = pipeline.read_errors([8], {{n: [d + "/n.json"] for n in ["W1inf"]}})
    for n in tables.TABLE1_NORMS: e[n] = 1.0
    tables.table1(e, d + "/t1.csv", d + "/t1.md", d + "/t1.tex")
elif stage == "figures":
    from signorini import figures
    e = pipeline.read_errors([8], {{"W1inf": [d + "/n.json"]}})
    e["L4"] = e["W14"] = 1.0
    figures.figure3(e, d + "/f3.pdf", d + "/f3.png")
    figures.figure2(load_npz(d + "/f.npz"), d + "/f2.pdf", d + "/f2.png")
elif stage == "runtime":
    pipeline.collect_runtime([], d + "/runtime.csv")
mods = sorted(m for m in sys.modules if m == "signorini" or m.startswith("signorini."))
print(json.dumps(mods))
"""
    for stage in ("solve", "norm", "sample", "errors", "eoc", "tables", "figures", "runtime"):
        out = subprocess.run([sys.executable, "-c", script, stage], capture_output=True, text=True, check=True)
        imported = set(json.loads(out.stdout.strip().splitlines()[-1]))
        declared = set()
        for rel in pipeline.STAGE_MODULES[stage]:
            name = "signorini." + rel.removesuffix(".py").replace("/", ".")
            declared.add(name.removesuffix(".__init__"))
        assert imported <= declared, f"{stage}: runs undeclared modules {sorted(imported - declared)}"


# --- the workflow on the smoke scene ---------------------------------------------------------


@pytest.fixture(scope="module")
def smoke_repo(tmp_path_factory):
    """A repository copy in which the smoke scene and the render stage (from smoke) have run."""
    repo = copy_repo(tmp_path_factory.mktemp("repo"))
    mine = {
        "scenes": {
            "mine": {
                "N": [8, 16],
                "norms": ["L2", "H1"],
                "solver": "active_set",
                "problem": PROBLEM,
            }
        }
    }
    (repo / "mine.yaml").write_text(yaml.safe_dump(mine))
    t0 = time.perf_counter()
    snakemake(
        repo,
        "-c2",
        "results/smoke/errors.csv",
        "results/smoke/eoc.csv",
        "results/mine/errors.csv",
        "--configfile",  # after the targets: --configfile takes several values
        "mine.yaml",
    )
    # the render stage, from the smoke scene (paper_figures/ of the copy)
    snakemake(repo, "-c2", "all", "--config", "figures_scene=smoke")
    print(f"smoke workflow: {time.perf_counter() - t0:.1f} s")
    return repo


def test_figure3_plans_only_l4_and_w14(tmp_path):
    copy_repo(tmp_path)
    proc = snakemake(tmp_path, "-n", "paper_figures/figure3.pdf")
    jobs = planned(proc)
    norms = {wc["norm"] for rule, wc in jobs if rule == "norm"}
    assert norms == {"L4", "W14"}
    assert sorted(int(wc["N"]) for rule, wc in jobs if rule == "solve") == [101, 201, 301, 401, 501]
    assert {rule for rule, _ in jobs} == {"solve", "norm", "figure3"}


@pytest.mark.slow
def test_smoke_csv_contract(smoke_repo):
    rows = list(csv.DictReader((smoke_repo / "results/smoke/errors.csv").open()))
    assert list(rows[0]) == ["N", "h", *NORMS]
    assert [int(r["N"]) for r in rows] == SMOKE_N
    for r in rows:
        assert float(r["h"]) == pytest.approx(1.0 / int(r["N"]), rel=1e-15)
        assert all(float(r[n]) > 0 for n in NORMS)
    eoc = list(csv.DictReader((smoke_repo / "results/smoke/eoc.csv").open()))
    assert list(eoc[0]) == ["N", "h", *NORMS]
    assert [r["N"] for r in eoc] == ["21", "41", "regression"]
    assert eoc[-1]["h"] == ""
    assert 1.5 < float(eoc[-1]["L4"]) < 2.5 and 0.7 < float(eoc[-1]["W14"]) < 1.3
    # a scene added with --configfile computes exactly its two norms
    mine = list(csv.DictReader((smoke_repo / "results/mine/errors.csv").open()))
    assert list(mine[0]) == ["N", "h", "L2", "H1"] and [int(r["N"]) for r in mine] == [8, 16]
    assert sorted(p.name for p in (smoke_repo / "results/mine/N8/norms").iterdir()) == ["H1.json", "L2.json"]


@pytest.mark.slow
def test_smoke_render_outputs(smoke_repo):
    figs = smoke_repo / "paper_figures"
    for name in ("table1.csv", "table1.md", "table1.tex", "table2.csv", "table2.md", "table2.tex"):
        assert (figs / name).stat().st_size > 0
    for name in ("figure2.pdf", "figure2.png", "figure3.pdf", "figure3.png"):
        assert (figs / name).read_bytes()[:4] in (b"%PDF", b"\x89PNG")
    t2 = (figs / "table2.csv").read_text().splitlines()
    assert t2[0] == "h,L4,L16,Linf,W14,W116,W1inf,H12" and t2[-2].startswith("regr.") and t2[-1].startswith("theo.")
    repro = (figs / "reproduction.md").read_text()
    assert "## Remarks on deviations" in repro
    assert (smoke_repo / "workflow/reference/deviation_remarks.md").read_text().strip() in repro
    runtime = list(csv.DictReader((figs / "runtime.csv").open()))
    assert {r["rule"] for r in runtime} == {"solve", "norm"} and len(runtime) == 3 + 3 * 7
    assert all(float(r["benchmark_wall_s"]) > 0 for r in runtime)


@pytest.mark.slow
def test_up_to_date_workflow_plans_nothing(smoke_repo):
    proc = snakemake(smoke_repo, "-n", "all", "--config", "figures_scene=smoke")
    assert planned_rules(proc) == set(), proc.stdout


def _plan_after_edit(repo: Path, module: str) -> set[str]:
    """Rules a dry run plans after an edit of ``module`` (a touch alone is not enough:
    Snakemake compares the checksums of small inputs whose mtime changed)."""
    path = repo / "src/signorini" / module
    text, st = path.read_text(), path.stat()
    try:
        path.write_text(text + "\n# an edit\n")
        future = time.time() + 5
        os.utime(path, (future, future))
        return planned_rules(snakemake(repo, "-n", "all", "--config", "figures_scene=smoke"))
    finally:
        path.write_text(text)
        os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns))


@pytest.mark.slow
def test_editing_figures_rerenders_figures_only(smoke_repo):
    assert _plan_after_edit(smoke_repo, "figures.py") == {"figure2", "figure3"}


@pytest.mark.slow
def test_editing_tables_rerenders_tables_only(smoke_repo):
    assert _plan_after_edit(smoke_repo, "tables.py") == {"table1", "table2", "reproduction"}


@pytest.mark.slow
def test_editing_norms_reruns_norms_and_render_but_no_solve(smoke_repo):
    rules = _plan_after_edit(smoke_repo, "norms.py")
    assert "norm" in rules and {"errors", "eoc", "table1", "table2", "figure3", "reproduction"} <= rules
    assert not rules & {"solve", "sample", "figure2"}


@pytest.mark.slow
def test_editing_a_solver_reruns_from_solve(smoke_repo):
    rules = _plan_after_edit(smoke_repo, "solvers/active_set.py")
    assert {"solve", "norm", "errors", "eoc", "table1", "table2", "figure3", "runtime"} <= rules
    assert "sample" not in rules  # u and f for Figure 2 do not depend on the solver


@pytest.mark.slow
def test_truncated_artifacts_are_detected_and_rebuilt(smoke_repo):
    res = smoke_repo / "results/smoke"
    npz, njson, errors = res / "N11/solution.npz", res / "N21/norms/L4.json", res / "errors.csv"
    before_u, before_l4, before_errors = load_npz(npz)["u"], load_json(njson)["value"], errors.read_text()
    # truncated cache files (newer than their inputs, as after a damaged copy)
    npz.write_bytes(npz.read_bytes()[: npz.stat().st_size // 3])
    njson.write_text(njson.read_text()[:40])
    errors.write_text(before_errors[: len(before_errors) - 30])
    # planning moves them aside; errors.csv is rebuilt, and so is the norm it needs ...
    jobs = planned(snakemake(smoke_repo, "-n", "results/smoke/errors.csv"))
    for path in (npz, njson, errors):
        assert not path.exists() and path.with_name(path.name + ".corrupt").exists()
    assert ("norm", {"scene": "smoke", "N": "21", "norm": "L4"}) in jobs and ("errors", {"scene": "smoke"}) in jobs
    # ... while the N11 norms, computed from the sound solution, stay valid; the solution
    # is rebuilt (never read) as soon as a job needs it, e.g. a norm not computed yet
    assert "solve" not in {rule for rule, _ in jobs}
    new_norm = "results/smoke/N11/norms/L2.json"
    assert ("solve", {"scene": "smoke", "N": "11"}) in planned(snakemake(smoke_repo, "-n", new_norm))
    snakemake(smoke_repo, "-c2", "results/smoke/errors.csv", "results/smoke/eoc.csv", new_norm)
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
    assert pipeline.artifact_ok(tmp_path / "errors.csv")
    for bad in (good[:-1], good[:-8], "N,h,L4\n11,0.09,\n"):
        (tmp_path / "errors.csv").write_text(bad)
        assert not pipeline.artifact_ok(tmp_path / "errors.csv"), bad
    (tmp_path / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\nregression,,1.9\n")
    assert pipeline.artifact_ok(tmp_path / "eoc.csv")
    (tmp_path / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\n")
    assert not pipeline.artifact_ok(tmp_path / "eoc.csv")
