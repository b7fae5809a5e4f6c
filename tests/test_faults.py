"""Faults that must never end in a wrong table with exit code 0: non-finite or negative norm
values, tables that lost a row, a scene whose errors vanish, artifacts unreadable by others."""

from __future__ import annotations

import ast
import os
import re
import signal
import stat
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import PROBLEM, ROOT

from signorini.pipeline.artifacts import CorruptArtifactError, load_json, save_json
from signorini.pipeline.config import ConfigError, check_config, load_config
from signorini.pipeline.integrity import artifact_ok, cached_artifacts, corrupt_artifacts
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.eoc import eoc_stage
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh, read_errors

ERRORS = "N,h,L4\n11,0.0909,0.04\n21,0.0476,0.012\n41,0.0244,0.0035\n"
EOC = "N,h,L4\n21,0.0476,1.8\n41,0.0244,1.9\nregression,,1.85\n"


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    d = tmp_path_factory.mktemp("faults")
    at = SceneMesh(PROBLEM, 8, "sw_ne")
    discretise_stage(at, d / "system.npz", d / "system.json")
    solve_stage(at, d / "system.npz", "active_set", d / "solution.npz", d / "solution.json")
    return d, at


@pytest.mark.parametrize("bad", [np.nan, np.inf, -1.0])
def test_a_non_finite_norm_value_fails_the_norm_job(solved, monkeypatch, tmp_path, bad):
    import signorini.studies.scene.norm as stage

    d, at = solved
    monkeypatch.setattr(stage, "evaluate_named_norms", lambda *args, **kwargs: {"L4": bad})
    with pytest.raises(ValueError, match="not a finite non-negative number"):
        norm_stage(at, d / "solution.npz", "L4", tmp_path / "L4.json", {})
    assert not (tmp_path / "L4.json").exists()


def test_a_nan_norm_artifact_never_reaches_a_table(solved, tmp_path):
    d, at = solved
    norm_stage(at, d / "solution.npz", "L4", tmp_path / "L4.json", {})
    art = load_json(tmp_path / "L4.json")
    save_json(tmp_path / "L4.json", {**art, "value": float("nan")})  # a well-formed artifact with NaN
    with pytest.raises(CorruptArtifactError, match="not a finite non-negative number"):
        read_errors([8], {"L4": [tmp_path / "L4.json"]})


@pytest.mark.parametrize("table, text", [("errors.csv", ERRORS), ("eoc.csv", EOC)])
def test_a_table_that_lost_a_row_is_out_of_date(tmp_path, table, text, capsys):
    """A complete table without one of the scene's N (``sed -i '3d'``, or the N list changed) is a
    valid file of another state: removed and rebuilt, and called out of date, not corrupt."""
    from signorini.pipeline.integrity import remove_stale

    scene = {"N": [11, 21, 41], "norms": ["L4"]}
    path = tmp_path / "s" / table
    path.parent.mkdir()
    path.write_text(text)
    assert not remove_stale(cached_artifacts(tmp_path, {"s": scene}), str, execute=True)
    lines = text.splitlines(keepends=True)
    path.write_text("".join(lines[:2] + lines[3:]))  # a complete-looking table without one N
    assert artifact_ok(path) and not corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene}))
    assert remove_stale(cached_artifacts(tmp_path, {"s": scene}), str, execute=True) == [str(path)]
    err = capsys.readouterr().err
    assert "out of date" in err and "the scene asks for" in err and "corrupt" not in err
    assert not path.exists() and not (tmp_path / "s" / f"{table}.corrupt").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-0.5"])
def test_a_table_with_a_non_finite_or_negative_error_is_caught(tmp_path, value):
    path = tmp_path / "errors.csv"
    path.write_text(ERRORS.replace("0.012", value))
    assert not artifact_ok(path)


def test_a_vanishing_error_or_a_single_mesh_stops_the_eoc_job(tmp_path):
    (tmp_path / "errors.csv").write_text(ERRORS.replace("0.012", "0.0"))
    with pytest.raises(ValueError, match="L4 error vanishes"):
        eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    (tmp_path / "errors.csv").write_text("N,h,L4\n11,0.0909,0.04\n")
    with pytest.raises(ValueError, match="at least two meshes"):
        eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    assert not (tmp_path / "eoc.csv").exists()


def test_a_scene_whose_errors_vanish_is_rejected():
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"]["problem"] = {**PROBLEM, "A": 0}
    with pytest.raises(ConfigError, match=r"scenes\.smoke\.problem\.A: 0 makes u ≡ 0"):
        check_config(config)


def test_artifacts_follow_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        save_json(tmp_path / "a.json", {"x": 1})
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.json").stat().st_mode) == 0o644


@pytest.mark.parametrize(
    ("N", "limit", "message"),
    [
        (10_000_000, None, r"N\[1\]: N = 10000000 needs about .* GB for its solve job"),
        (30_000, None, r"N\[1\]: N = 30000 needs about 1758.3 GB"),
        (1001, 1000, r"N\[1\]: N = 1001 needs about 2.4 GB .* more than the 1.0 GB available"),
    ],
)
def test_a_mesh_that_cannot_fit_is_refused_before_any_job(N, limit, message):
    config = load_config(ROOT / "workflow/config.yaml")
    config = {"figures_scene": "smoke", "scenes": {"smoke": {**config["scenes"]["smoke"], "N": [11, N]}}}
    with pytest.raises(ConfigError, match=message):
        check_config(config, limit)


@pytest.mark.parametrize(
    ("solver", "options", "message"),
    [
        ("active_set", {"max_iters": 5}, "solver_options.max_iters: not an option of active_set_solve"),
        ("active_set", {"max_iter": "5"}, "solver_options.max_iter: '5' is not of type int"),
        ("cvxpy_osqp", {"max_iters": 5}, "solver_options.max_iters: not an option of cvxpy_solve/OSQP"),
        ("cvxpy_scs", {"max_iter": 5}, "solver_options.max_iter: not an option of cvxpy_solve/SCS"),
        ("cvxpy_clarabel", {"max_iter": "5"}, "solver_options.max_iter: '5' is not of type int"),
        ("cvxpy", {"qp_solver": "OSQP", "tol": "1e-8"}, "solver_options.tol: '1e-8' is not of type float"),
        ("cvxpy_osqp", {"normalize": "yes"}, "solver_options.normalize: 'yes' is not of type bool"),
        ("multigrid", {"backend": "cholmod"}, "solver_options.backend: not an option of multigrid_solve"),
        ("multigrid", {"inner_rtol": "1e-8"}, "solver_options.inner_rtol: '1e-8' is not of type float"),
        ("auto", {"amg": "classical"}, "solver_options.amg: not an option of active_set_solve and multigrid_solve"),
    ],
)
def test_unknown_or_mistyped_solver_options_are_refused(solver, options, message):
    """Named before any job runs (they used to fail inside the solve job, after assembly, with an
    unnamed TypeError); valid options of the same route pass."""
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"].update(solver=solver, solver_options=options)
    with pytest.raises(ConfigError, match=f"scenes.smoke.{message}"):
        check_config(config)
    valid = {
        "active_set": {"max_iter": 50, "kkt_tol": 1e-11},
        "cvxpy": {"qp_solver": "OSQP", "tol": 1e-8},
        "multigrid": {"amg": "smoothed_aggregation", "inner_rtol": 1e-9, "max_coarse": 100},
        "auto": {"max_iter": 50, "kkt_tol": 1e-11, "frontier_growth": True},
    }
    config["scenes"]["smoke"]["solver_options"] = valid.get(solver, {"tol": 1e-8, "normalize": True, "verbose": False})
    check_config(config)


def test_mistyped_options_of_a_study_or_atlas_column_are_refused():
    from signorini.studies.stability.atlas import AtlasConfigError, check_atlases
    from signorini.studies.work_precision.study import StudyConfigError, study_configs

    study = {"configs": {"osqp": {"solver": "OSQP", "options": {"polishing": "no"}}}}
    with pytest.raises(StudyConfigError, match="study.configs.osqp.options.polishing: 'no' is not of type int"):
        study_configs(study)
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["stability"]["atlas"]["solvers"]["scs"]["options"]["time_limit"] = 60
    with pytest.raises(AtlasConfigError, match="atlas.solvers.scs.options.time_limit: not an option of cvxpy_solve"):
        check_atlases(config)


def test_a_solution_of_another_problem_is_refused(solved, tmp_path):
    """A well-formed solution artifact copied over from a scene with another problem (A = 20)."""
    from signorini.pipeline.artifacts import load_npz, recording, save_npz

    d, at = solved
    foreign = tmp_path / "solution.npz"
    with recording({"rule": "solve", "code": "x", "params": {"problem": {**PROBLEM, "A": 20}}}):
        save_npz(foreign, **load_npz(d / "solution.npz"))
    with pytest.raises(CorruptArtifactError, match="solves the problem"):
        norm_stage(at, foreign, "L4", tmp_path / "L4.json", {})
    assert not (tmp_path / "L4.json").exists()


@pytest.mark.slow
def test_an_edit_during_a_run_is_not_trusted(built_repo, tmp_path):
    """A norm job that imported the old code but finished after an edit leaves an artifact newer
    than the edit: modification times call it current, its recorded code digest does not."""
    from helpers import clone_built, planned, snakemake

    repo = clone_built(built_repo, tmp_path / "repo")
    module = repo / "src/signorini/fem/norms.py"
    st = module.stat()
    module.write_text(module.read_text() + "\n# edited while the norm jobs ran\n")
    os.utime(module, ns=(st.st_atime_ns, st.st_mtime_ns))  # the jobs' outputs are newer than the edit
    norm_json = repo / "results/smoke/N21/norms/L4.json"
    before = norm_json.read_bytes()
    proc = snakemake(repo, "-n", "results/smoke/errors.csv")  # read-only: named, nothing removed
    assert "computed by other code" in proc.stderr and norm_json.read_bytes() == before
    ran = planned(snakemake(repo, "-c2", "results/smoke/errors.csv"))
    norms = {(wc["N"], wc["norm"]) for rule, wc in ran if rule == "norm" and wc["scene"] == "smoke"}
    assert len(norms) == 3 * 7 and ("errors", {"scene": "smoke"}) in ran
    assert not {"discretise", "solve"} & {rule for rule, _ in ran}  # their code did not change


def test_a_hand_edited_norm_value_is_caught(solved, tmp_path):
    d, at = solved
    path = tmp_path / "L4.json"
    norm_stage(at, d / "solution.npz", "L4", path, {})
    value = load_json(path)["value"]
    path.write_text(path.read_text().replace(repr(value), repr(2 * value)))  # a well-formed edit
    with pytest.raises(CorruptArtifactError, match="checksum mismatch"):
        load_json(path)
    assert not artifact_ok(path)


@pytest.mark.slow
def test_an_input_replaced_under_its_consumers_is_not_trusted(built_repo, tmp_path, monkeypatch):
    """A valid ``system.npz`` of other content put in place with the old modification time: the
    solution computed from the old one is removed and rebuilt, and a job refuses it meanwhile."""
    from helpers import clone_built, planned, snakemake

    from signorini.pipeline.artifacts import load_npz, npz_provenance, recording, save_npz
    from signorini.pipeline.joblog import StaleInputError, check_inputs

    repo = clone_built(built_repo, tmp_path / "repo")
    system = repo / "results/smoke/N21/system.npz"
    st = system.stat()
    arrays = load_npz(system)
    with recording(npz_provenance(arrays)):
        save_npz(system, **{k: v for k, v in arrays.items() if k != "_provenance"} | {"b": 2 * arrays["b"]})
    os.utime(system, ns=(st.st_atime_ns, st.st_mtime_ns))  # modification times see no change
    monkeypatch.chdir(repo)  # provenance names inputs relative to the workflow directory
    with pytest.raises(StaleInputError, match="computed from another results/smoke/N21/system.npz"):
        check_inputs(["results/smoke/N21/solution.npz"])
    proc = snakemake(repo, "-n", "results/smoke/errors.csv")  # read-only: named, nothing removed
    assert "solution.npz was computed from another results/smoke/N21/system.npz" in proc.stderr
    ran = planned(snakemake(repo, "-c2", "results/smoke/errors.csv"))
    assert ("solve", {"scene": "smoke", "N": "21"}) in ran and ("errors", {"scene": "smoke"}) in ran
    assert "discretise" not in {rule for rule, _ in ran}  # the replaced system is valid: it is used
    check_inputs(["results/smoke/N21/solution.npz"])


def test_temporaries_left_by_a_killed_job_are_removed(tmp_path, monkeypatch):
    """``kill -9`` during an atomic write leaves ``.<name>.<random>.tmp``; the next run that
    executes jobs deletes it, unless another run holds the directory's lock (its jobs may be
    writing) or the file is fresh (a run with ``--nolock``)."""
    from signorini.pipeline.integrity import leftover_temporaries, remove_leftover_temporaries

    monkeypatch.chdir(tmp_path)
    old = tmp_path / "results/smoke/N11/.solution.npz.x1y2.tmp"
    fresh = tmp_path / "results/smoke/N21/.solution.npz.a3b4.tmp"
    for path in (old, fresh):
        path.parent.mkdir(parents=True)
        path.write_bytes(b"PK\x03\x04 half an archive")
    os.utime(old, (1e9, 1e9))
    lock = tmp_path / ".snakemake/locks/0.input.lock"
    lock.parent.mkdir(parents=True)
    lock.write_text("")
    assert leftover_temporaries(["results"]) == []  # another run is active
    lock.unlink()
    assert remove_leftover_temporaries(["results"], execute=False) == [] and old.exists()  # read-only
    assert remove_leftover_temporaries(["results"], execute=True) == [old.relative_to(tmp_path)]
    assert not old.exists() and fresh.exists()


@pytest.mark.slow
def test_a_damaged_benchmark_file_is_rebuilt(built_repo, tmp_path):
    """A benchmark ``.tsv`` that lost its row is moved aside, and when ``runtime.csv`` has to be
    rebuilt its job reruns, instead of the run failing until someone repairs the file."""
    from helpers import clone_built, planned, snakemake

    repo = clone_built(built_repo, tmp_path / "repo")
    tsv = repo / "results/smoke/benchmarks/N21/solve.tsv"
    header = tsv.read_text().splitlines()[0]
    assert artifact_ok(tsv)
    tsv.write_text(header + "\n")
    assert not artifact_ok(tsv)
    ran = planned(snakemake(repo, "-c2", "--forcerun", "runtime", "--", "paper_figures/runtime.csv"))
    assert ("solve", {"scene": "smoke", "N": "21"}) in ran and ("runtime", {}) in ran
    assert artifact_ok(tsv) and (repo / "results/smoke/benchmarks/N21/solve.tsv.corrupt").exists()


def test_a_yaml_syntax_error_is_named_with_file_and_line(tmp_path, monkeypatch, capsys):
    """Snakemake says only that a config file is not valid YAML; the Snakefile checks the shipped
    config first, and ``python -m signorini.pipeline.config`` a file given with ``--configfile``."""
    from signorini.pipeline.config import load_yaml, main

    bad = tmp_path / "mine.yaml"
    bad.write_text("scenes:\n  mine:\n    N: [11, 21\n    norms: [L4]\n")
    with pytest.raises(ConfigError, match=r"mine\.yaml:4:10: expected ',' or '\]'"):
        load_yaml(bad)
    monkeypatch.chdir(ROOT)
    assert main([str(bad)]) == 1 and "mine.yaml:4:10" in capsys.readouterr().err
    good = tmp_path / "good.yaml"
    problem = "    problem: {x0: 0.5, R: 0.45, A: 10, c: 1}\n"
    good.write_text(bad.read_text().replace("21\n", "21]\n") + "    solver: active_set\n" + problem)
    scenes = len(load_yaml("workflow/config.yaml")["scenes"]) + 1
    assert main([str(good)]) == 0 and f"({scenes} scenes)" in capsys.readouterr().out


def test_the_damage_check_covers_every_kind_of_artifact(tmp_path):
    """The theory, work-precision and atlas artifacts and the benchmark files are checked like
    the chain's: each damaged one is found, an intact one is not."""
    kinds = [
        "N11/theory.json",
        "N11/work_precision/osqp.json",
        "atlas/A_1.json",
        "N11/norms/L4.json",
        "N11/solution.json",
    ]
    for name in kinds:
        save_json(tmp_path / "s" / name, {"value": 1.0})
    tsv = tmp_path / "s/benchmarks/N11/solve.tsv"
    tsv.parent.mkdir(parents=True)
    tsv.write_text("s\th:m:s\tmax_rss\n0.5\t0:00:00\t100.0\n")
    scene = {"N": [11], "atlas": {}}
    assert corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene})) == []
    for name in kinds:
        (tmp_path / "s" / name).write_text((tmp_path / "s" / name).read_text().replace("1.0", "2.0"))
    tsv.write_text("s\th:m:s\tmax_rss\n")
    damaged = corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene}))
    assert sorted(damaged) == sorted(str(tmp_path / "s" / name) for name in [*kinds, "benchmarks/N11/solve.tsv"])


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_a_run_killed_during_a_job_recovers_bit_for_bit(built_repo, tmp_path, sig):
    """``kill -9`` of the whole run (or Ctrl-C) while a solve job runs: never a partial file under
    a final name, and the next run that requests the file (after ``--unlock`` for ``kill -9``)
    writes the same bytes."""
    from helpers import SNAKEMAKE, clone_built, snakemake

    repo = clone_built(built_repo, tmp_path / "repo")
    solution = repo / "results/smoke/N41/solution.npz"
    before = solution.read_bytes()
    started = repo / "results/smoke/logs/N41/solve.log"
    started.unlink()
    run = subprocess.Popen(
        [SNAKEMAKE, "-c1", "--forcerun", "solve", "--", "results/smoke/N41/solution.npz"],
        cwd=repo,
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 300
    while not started.exists() and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert run.poll() is None, "the run ended before its solve job started"
    os.killpg(run.pid, sig)
    run.wait(timeout=120)
    assert not solution.exists() or artifact_ok(solution)
    for leftover in (repo / "results").rglob(".*.tmp"):  # as if the next run came minutes later
        os.utime(leftover, (1e9, 1e9))
    if sig == signal.SIGKILL:
        snakemake(repo, "--unlock")
    snakemake(repo, "-c1", "results/smoke/N41/solution.npz", "results/smoke/errors.csv")
    assert solution.read_bytes() == before
    assert not list((repo / "results").rglob(".*.tmp"))


# --- provenance includes the parameters; words match the state --------------------------------


def test_an_artifact_computed_with_other_parameters_is_out_of_date(tmp_path, capsys, monkeypatch):
    """Its recorded code and inputs are current, only the parameters a job would get now differ
    (A 10 -> 20): out of date, and so is everything computed from it and the scene's tables."""
    from signorini.pipeline.artifacts import content_digest, recording
    from signorini.pipeline.integrity import remove_stale, stale_artifacts

    monkeypatch.chdir(tmp_path)  # the workflow names artifacts relative to its directory
    scene = Path("results/s")
    system, norm = scene / "N11/system.json", scene / "N11/norms/L4.json"
    with recording({"rule": "discretise", "code": "c", "params": {"problem": PROBLEM}, "inputs": {}}):
        save_json(system, {"n": 1})
    inputs = {str(system): content_digest(system)}
    with recording({"rule": "norm", "code": "c", "params": {"problem": PROBLEM}, "inputs": inputs}):
        save_json(norm, {"value": 1.0})
    (scene / "errors.csv").write_text(ERRORS)

    def cached():
        return cached_artifacts("results", {"s": {"N": [11, 21, 41], "norms": ["L4"]}})

    def code(rule):
        return "c"

    assert stale_artifacts(cached(), code, lambda path, prov: {"problem": PROBLEM}) == []
    now = {"problem": {**PROBLEM, "A": 20}}
    stale = dict(stale_artifacts(cached(), code, lambda path, prov: now))
    assert set(stale) == {str(system), str(norm)}
    assert '"A": 10' in stale[str(system)] and '"A": 20' in stale[str(system)]
    removed = remove_stale(cached(), code, False, lambda path, prov: now)
    assert set(removed) == {str(system), str(norm), str(scene / "errors.csv")} and system.exists()  # read-only
    assert "out of date" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("block", "reason"),
    [
        ({"N": [11, 21], "norms": ["L4"]}, "holds the rows N = 11, 21, 41, the scene asks for 11, 21"),
        ({"N": [11, 21, 41, 81], "norms": ["L4"]}, "the scene asks for 11, 21, 41, 81"),
        ({"N": [11, 21, 41], "norms": ["L4", "H12"]}, "has the norms L4, the scene asks for L4, H12"),
        ({"N": [11, 21, 41], "norms": []}, "has the norms L4, the scene asks for none"),
    ],
)
def test_a_table_of_other_meshes_or_norms_is_out_of_date_not_corrupt(tmp_path, capsys, block, reason):
    from signorini.pipeline.integrity import quarantine_corrupt, remove_stale

    (tmp_path / "s").mkdir()
    (tmp_path / "s/errors.csv").write_text(ERRORS)
    assert quarantine_corrupt(cached_artifacts(tmp_path, {"s": block})) == []
    assert remove_stale(cached_artifacts(tmp_path, {"s": block}), str, execute=True) == [str(tmp_path / "s/errors.csv")]
    err = capsys.readouterr().err
    assert reason in err and "out of date" in err and "corrupt" not in err
    assert not list(tmp_path.rglob("*.corrupt"))


# --- integrity checks are not optional ----------------------------------------------------------


@pytest.mark.parametrize("kind", ["json", "npz", "large_npz"])
def test_a_checksummed_artifact_without_its_checksum_is_damaged(tmp_path, monkeypatch, kind):
    """A norm JSON edited by hand with its ``_checksum`` removed, an archive rewritten without it:
    both fail their check (the checksum is part of the format, not optional)."""
    import json

    import signorini.pipeline.integrity as cache
    from signorini.pipeline.artifacts import load_npz, save_npz

    if kind == "json":
        path = tmp_path / "L4.json"
        save_json(path, {"value": 0.04})
        data = json.loads(path.read_text())
        del data["_checksum"]
        path.write_text(json.dumps({**data, "value": 0.004}))
        with pytest.raises(CorruptArtifactError, match="no checksum"):
            load_json(path)
    else:
        path = tmp_path / "solution.npz"
        save_npz(path, u=np.arange(4.0))
        np.savez(path, **{k: v for k, v in np.load(path).items() if k != "_checksum"})
        with pytest.raises(CorruptArtifactError, match="no checksum"):
            load_npz(path)
        if kind == "large_npz":  # checked structurally, by its zip directory
            monkeypatch.setattr(cache, "CHECKSUM_MAX_BYTES", 0)
    assert not artifact_ok(path)
    assert corrupt_artifacts([path]) == [str(path)]


# --- text I/O names its encoding ------------------------------------------------------------------

# calls that read or write text and take an ``encoding`` (open and Path.open unless binary, pathlib,
# pandas, logging, io, subprocess with text=True)
_TEXT_CALLS = {"read_text", "write_text", "read_csv", "to_csv", "read_table", "read_json", "to_json"}
_TEXT_CALLS |= {"FileHandler", "TextIOWrapper"}


def _mode(call, index: int):
    for kw in call.keywords:
        if kw.arg == "mode":
            return kw.value.value if isinstance(kw.value, ast.Constant) else None
    if len(call.args) > index:
        return call.args[index].value if isinstance(call.args[index], ast.Constant) else None
    return "r"


def unnamed_encodings(source: str) -> list[tuple[int, str]]:
    """(line, call) of every text I/O call in ``source`` that does not name its encoding."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Call) or {kw.arg for kw in node.keywords} & {"encoding", None}:
            continue
        func = node.func
        name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
        owner = getattr(func.value, "id", None) if isinstance(func, ast.Attribute) else None
        if name in ("open", "fdopen"):  # open(path, mode), os.fdopen(fd, mode), Path.open(mode)
            index = 0 if isinstance(func, ast.Attribute) and owner not in ("os", "io") else 1
            mode = _mode(node, index)
            bad = mode is None or "b" not in mode
        elif name == "to_csv":  # with no target it returns the text: no encoding involved
            bad = bool(node.args) or any(kw.arg == "path_or_buf" for kw in node.keywords)
        elif name in ("run", "Popen", "check_output", "check_call", "call") and owner == "subprocess":
            bad = any(kw.arg in ("text", "universal_newlines") for kw in node.keywords)
        else:
            bad = name in _TEXT_CALLS
        if bad:
            found.append((node.lineno, ast.unparse(node)[:120]))
    return found


def test_the_encoding_check_finds_what_it_should():
    source = (
        "open(p)\nopen(p, 'w')\nopen(p, 'rb')\nPath(p).open()\nPath(p).open('wb')\np.read_text()\n"
        "p.write_text(s, encoding='utf-8')\nos.fdopen(fd, 'w')\nos.fdopen(fd, 'wb')\npd.read_csv(p)\n"
        "df.to_csv()\ndf.to_csv(p)\nsubprocess.run(c, text=True)\nsubprocess.run(c)\nlogging.FileHandler(p)\n"
    )
    assert [line for line, _ in unnamed_encodings(source)] == [1, 2, 4, 6, 8, 10, 12, 13, 15]


def test_no_text_io_call_leaves_its_encoding_to_the_locale():
    """Every file of src/, workflow/ (scripts, peers, the Snakefile's rules), benchmarks/ and
    notebooks/ names the encoding of every text it reads or writes."""
    files = [p for d in ("src", "workflow", "benchmarks", "notebooks") for p in sorted((ROOT / d).rglob("*.py"))]
    found = [f"{p.relative_to(ROOT)}:{line}: {call}" for p in files for line, call in unnamed_encodings(p.read_text())]
    # the Snakefile and the rule files are not Python: no call of these kinds at all there
    rules = [ROOT / "Snakefile", *sorted((ROOT / "workflow/rules").glob("*.smk"))]
    pattern = re.compile(r"\b(open|read_text|write_text|read_csv|to_csv)\(")
    found += [f"{p.relative_to(ROOT)}: {m.group(0)}" for p in rules for m in pattern.finditer(p.read_text())]
    assert not found, "\n".join(found)


# --- make setup is atomic -------------------------------------------------------------------------

# Stand-ins for the interpreter, pip and uv that `make setup` calls: they behave like the real
# ones where it matters (pip writes uv's metadata, then the binary, and does nothing once the
# metadata is there: "Requirement already satisfied") and can be made to hang, to be interrupted.
FAKE_PYTHON = """#!/bin/bash
[ "$1 $2" = "-m venv" ] || exit 2
dir="$3"; mkdir -p "$dir/bin" "$dir/lib"
cat > "$dir/bin/pip" <<PIP
#!/bin/bash
[ -e "$dir/lib/uv.dist-info" ] && exit 0
mkdir -p "$dir/lib/uv.dist-info"
printf 'half a binary' > "$dir/bin/uv"
[ -n "\\$FAKE_HANG_PIP" ] && { touch "\\$FAKE_HANG_PIP"; sleep 60; }
cp "$FAKE_UV" "$dir/bin/uv" && chmod +x "$dir/bin/uv"
PIP
chmod +x "$dir/bin/pip"
"""
FAKE_UV = """#!/bin/bash
case "$1" in
  --version) echo "uv 0.0.0 (stand-in)" ;;
  venv) for arg; do last="$arg"; done; mkdir -p "$last/bin"
        printf '#!/bin/sh\\nexit 0\\n' > "$last/bin/python"; chmod +x "$last/bin/python" ;;
  pip) if [ "$2" = sync ] && [ -n "$FAKE_HANG_SYNC" ]; then touch "$FAKE_HANG_SYNC"; sleep 60; fi ;;
esac
"""


def _make_setup(repo: Path, hang: str | None = None, **env: str) -> subprocess.Popen:
    env = {**os.environ, "FAKE_UV": str(repo / "fake-uv"), **env}
    if hang:
        env[hang] = str(repo / "hanging")
    return subprocess.Popen(
        ["make", "setup", "UV=", f"PYTHON={repo / 'fake-python'}"],
        cwd=repo,
        env=env,
        start_new_session=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        encoding="utf-8",
    )


@pytest.fixture
def setup_copy(tmp_path):
    import shutil

    for name in ("Makefile", "environment.lock", "pyproject.toml"):
        shutil.copy2(ROOT / name, tmp_path / name)
    for name, text in (("fake-python", FAKE_PYTHON), ("fake-uv", FAKE_UV)):
        (tmp_path / name).write_text(text)
        (tmp_path / name).chmod(0o755)
    return tmp_path


@pytest.mark.parametrize("hang", ["FAKE_HANG_PIP", "FAKE_HANG_SYNC"])
def test_an_interrupted_make_setup_leaves_nothing_that_fails_the_next(setup_copy, hang):
    """Ctrl-C while uv is being installed (or while the venv is synced): the next ``make setup``
    succeeds; no half-written .tools/bin/uv, no stamp that trusts a half-synced venv."""
    run = _make_setup(setup_copy, hang)
    deadline = time.monotonic() + 60
    while not (setup_copy / "hanging").exists() and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert run.poll() is None, run.stdout.read()
    os.killpg(run.pid, signal.SIGINT)
    run.wait(timeout=30)
    assert not (setup_copy / ".venv/.installed-from-lock").exists()
    again = _make_setup(setup_copy)
    out, _ = again.communicate(timeout=60)
    assert again.returncode == 0, out
    assert subprocess.run([setup_copy / ".tools/bin/uv", "--version"], capture_output=True).returncode == 0
    assert (setup_copy / ".venv/.installed-from-lock").exists()


def test_a_broken_uv_left_by_an_older_set_up_is_replaced(setup_copy):
    """A .tools whose uv was cut off (not executable, its metadata installed) is not trusted."""
    (setup_copy / ".tools/bin").mkdir(parents=True)
    (setup_copy / ".tools/lib/uv.dist-info").mkdir(parents=True)
    (setup_copy / ".tools/bin/uv").write_text("half a binary")
    run = _make_setup(setup_copy)
    out, _ = run.communicate(timeout=60)
    assert run.returncode == 0, out
    version = subprocess.run([setup_copy / ".tools/bin/uv", "--version"], capture_output=True, encoding="utf-8")
    assert "stand-in" in version.stdout


# --- end to end, on a small built copy ------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny_built(tmp_path_factory):
    """A repository copy whose rendered scene is ``tiny`` (the smoke scene on N = 11, 21: every norm
    the paper's outputs need), with ``all`` built: the small workflow the fault tests below damage."""
    from helpers import copy_repo, snakemake

    repo = copy_repo(tmp_path_factory.mktemp("tiny"))
    path = repo / "workflow/config.yaml"
    config = yaml.safe_load(path.read_text(encoding="utf-8"))
    config["scenes"]["tiny"] = {**config["scenes"]["smoke"], "N": [11, 21]}
    config["figures_scene"] = "tiny"
    path.write_text(yaml.safe_dump(config, sort_keys=False), encoding="utf-8")
    snakemake(repo, "-c2", "all", timeout=3600)
    return repo


def _set_scene(repo: Path, **block) -> None:
    path = repo / "workflow/config.yaml"
    config = yaml.safe_load(path.read_text(encoding="utf-8"))
    config["scenes"]["tiny"].update(block)
    path.write_text(yaml.safe_dump(config, sort_keys=False), encoding="utf-8")


def _set_config(repo: Path, **top) -> None:
    path = repo / "workflow/config.yaml"
    config = yaml.safe_load(path.read_text(encoding="utf-8"))
    config.update(top)
    path.write_text(yaml.safe_dump(config, sort_keys=False), encoding="utf-8")


def _tree(repo: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(repo)): p.read_bytes()
        for root in ("results", "paper_figures")
        for p in sorted((repo / root).rglob("*"))
        if p.is_file()
    }


@pytest.mark.slow
def test_a_changed_parameter_or_scene_reruns_without_snakemakes_metadata(tiny_built, tmp_path):
    """``.snakemake`` deleted and ``--rerun-triggers mtime``: the amplitude doubled doubles every
    error (the problem is positively homogeneous in A), a shortened norm list leaves exactly its
    columns, a changed N list exactly its rows; the tables are called out of date, never corrupt."""
    import shutil

    from helpers import clone_built, snakemake

    repo = clone_built(tiny_built, tmp_path / "repo")
    errors = repo / "results/tiny/errors.csv"
    before = read_errors_csv(errors)
    shutil.rmtree(repo / ".snakemake")
    _set_scene(repo, problem={**PROBLEM, "A": 20})
    proc = snakemake(repo, "-n", "--rerun-triggers", "mtime", "--", "results/tiny/eoc.csv")
    assert "out of date: results/tiny/N11/solution.npz" in proc.stderr and errors.read_text() == before.text
    proc = snakemake(repo, "-c2", "--rerun-triggers", "mtime", "--", "results/tiny/eoc.csv")
    after = read_errors_csv(errors)
    assert after.header == before.header and after.rows.keys() == before.rows.keys()
    for N, row in before.rows.items():
        np.testing.assert_allclose(after.rows[N], 2 * np.asarray(row), rtol=1e-9)
    # the paper's outputs need all of its norms: render another scene while tiny's list is short
    _set_config(repo, figures_scene="smoke")
    _set_scene(repo, norms=["L4", "H12"])
    proc = snakemake(repo, "-c2", "--rerun-triggers", "mtime", "--", "results/tiny/eoc.csv")
    assert read_errors_csv(errors).header == ["N", "h", "L4", "H12"]
    assert read_errors_csv(repo / "results/tiny/eoc.csv").header == ["N", "h", "L4", "H12"]
    _set_scene(repo, N=[11, 21, 31])
    proc2 = snakemake(repo, "-c2", "--rerun-triggers", "mtime", "--", "results/tiny/eoc.csv")
    assert list(read_errors_csv(errors).rows) == ["11", "21", "31"]
    for out in (proc, proc2):
        assert "out of date: results/tiny/errors.csv" in out.stderr and "corrupt" not in out.stderr
    assert not list((repo / "results").rglob("*.corrupt"))


@pytest.mark.slow
def test_the_papers_tables_follow_a_changed_mesh_list_without_snakemakes_metadata(tiny_built, tmp_path):
    """The rendered scene's N list changed with ``.snakemake`` gone (mtime trigger): Tables 1-2,
    Figure 3 and the reproduction report are out of date and rendered for exactly the new meshes."""
    import shutil

    from helpers import clone_built, snakemake

    repo = clone_built(tiny_built, tmp_path / "repo")
    shutil.rmtree(repo / ".snakemake")
    _set_scene(repo, N=[11, 21, 31])
    proc = snakemake(repo, "-c2", "--rerun-triggers", "mtime", "--", "all")
    assert "out of date: " in proc.stderr and "paper_figures/table1.csv holds the rows h = 1/11, 1/21" in proc.stderr
    table1 = read_errors_csv(repo / "paper_figures/table1.csv")
    table2 = read_errors_csv(repo / "paper_figures/table2.csv")
    assert list(table1.rows) == ["1/11", "1/21", "1/31"] and list(table2.rows) == ["1/21", "1/31", "regr.", "theo."]
    assert "1/31" in (repo / "paper_figures/reproduction.md").read_text(encoding="utf-8")


def test_rendered_tables_of_other_meshes_are_named(tmp_path):
    from signorini.pipeline.integrity import rendered_mismatch

    t1, t2 = tmp_path / "table1.csv", tmp_path / "table2.csv"
    t1.write_text("h,L4\n1/11,1e-3\n1/21,3e-4\n", encoding="utf-8")
    t2.write_text("h,L4\n1/21,1.9\nregr.,1.9\ntheo.,2.0\n", encoding="utf-8")
    tables = {"table1": t1, "table2": t2}
    assert rendered_mismatch(tables, [11, 21]) is None
    assert "holds the rows h = 1/11, 1/21" in rendered_mismatch(tables, [11, 21, 41])
    assert rendered_mismatch({"table1": tmp_path / "absent.csv"}, [11]) is None


class _Table:
    def __init__(self, text: str) -> None:
        import csv

        self.text = text
        rows = list(csv.reader(text.splitlines()))
        self.header = rows[0]
        self.rows = {row[0]: [float(v) for v in row[2:]] for row in rows[1:]}


def read_errors_csv(path: Path) -> _Table:
    return _Table(path.read_text(encoding="utf-8"))


READ_ONLY_CALLS = [
    ["-n"],
    ["--dry-run"],
    ["--dry-r"],  # an abbreviated long option, as argparse accepts it
    ["--dryrun"],
    ["-nc2"],  # combined short flags
    ["-pnc2"],
    ["-c2", "-n"],
    ["--cores=2", "--dry-ru"],
    ["--touch"],
    ["--profile", "{profile}"],  # dry-run: true in a profile
    ["--summary"],
    ["-S"],
    ["--lint"],
    ["-l"],
    ["--list-changes", "code"],
    ["--rulegraph", "dot"],
]


@pytest.mark.slow
def test_read_only_calls_change_nothing_however_spelled(tiny_built, tmp_path):
    """With every norm artifact out of date (a comment added to the norms module) and one norm
    artifact damaged, no spelling of a read-only call Snakemake accepts removes or moves anything;
    the dry runs name what a run would do."""
    from helpers import clone_built, snakemake

    repo = clone_built(tiny_built, tmp_path / "repo")
    module = repo / "src/signorini/fem/norms.py"
    module.write_text(module.read_text(encoding="utf-8") + "\n# a comment\n", encoding="utf-8")
    damaged = repo / "results/tiny/N21/norms/L4.json"
    damaged.write_text(damaged.read_text(encoding="utf-8")[:50], encoding="utf-8")
    profile = tmp_path / "dry profile"
    profile.mkdir()
    (profile / "config.yaml").write_text("dry-run: true\ncores: 2\n", encoding="utf-8")
    before = _tree(repo)
    for call in READ_ONLY_CALLS:
        args = [arg.format(profile=profile) for arg in call]
        proc = snakemake(repo, *args, "--", "results/tiny/eoc.csv", check=False, timeout=900)
        assert _tree(repo) == before, (args, proc.stderr[-3000:])
        if "-n" in args[0] or "dry" in " ".join(args) or args[0] == "--profile":
            assert "out of date: results/tiny/N11/norms/L4.json" in proc.stderr, (args, proc.stderr[-3000:])
            assert f"damaged artifact {damaged.relative_to(repo)}" in proc.stderr, args


def non_utf8_locale(tmp_path: Path) -> dict[str, str]:
    """The environment of a Turkish Latin-5 locale (ISO-8859-9), generated with localedef into
    ``tmp_path``; without localedef, the C locale with Python's UTF-8 mode and coercion off (ASCII)."""
    import shutil

    out = tmp_path / "locale"
    out.mkdir()
    if shutil.which("localedef"):
        subprocess.run(["localedef", "-i", "tr_TR", "-f", "ISO-8859-9", str(out / "tr_TR.ISO-8859-9")], check=False)
        if (out / "tr_TR.ISO-8859-9").exists():
            return {"LOCPATH": str(out), "LC_ALL": "tr_TR.ISO-8859-9", "PYTHONUTF8": "0"}
    return {"LC_ALL": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"}


@pytest.mark.slow
def test_the_chain_writes_the_same_bytes_under_a_non_utf8_locale(tiny_built, tmp_path):
    """The scene's tables, Tables 1-2 and the reproduction report rebuilt under a Latin-5 locale are
    byte for byte the ones built under UTF-8 (they used to read the remarks as Latin-5)."""
    import sys

    from helpers import SNAKEMAKE, clone_built

    repo = clone_built(tiny_built, tmp_path / "repo")
    env = {**os.environ, **non_utf8_locale(tmp_path), "PYTHONDONTWRITEBYTECODE": "1"}
    probe = [sys.executable, "-c", "import locale; print(locale.getpreferredencoding())"]
    assert "utf" not in subprocess.run(probe, env=env, capture_output=True, encoding="ascii").stdout.lower()
    rules = ["errors", "eoc", "table1", "table2", "reproduction"]
    proc = subprocess.run(
        [SNAKEMAKE, "-c2", "--forcerun", *rules, "--", "all"], cwd=repo, env=env, capture_output=True, timeout=1800
    )
    assert proc.returncode == 0, proc.stderr.decode("utf-8", "replace")[-3000:]
    outputs = ["results/tiny/errors.csv", "results/tiny/eoc.csv", "paper_figures/reproduction.md"]
    outputs += [f"paper_figures/table{k}.{ext}" for k in (1, 2) for ext in ("csv", "md", "tex")]
    for path in outputs:
        assert (repo / path).stat().st_mtime > (tiny_built / path).stat().st_mtime, path  # rebuilt
        assert (repo / path).read_bytes() == (tiny_built / path).read_bytes(), path


@pytest.mark.slow
def test_the_workflow_runs_from_another_directory_and_a_checkout_with_spaces(tiny_built, tmp_path):
    """``snakemake -s '<checkout with spaces>/Snakefile' -d '<another dir>'`` started from a third
    directory: the config, references and package come from the checkout, the results go to -d."""
    from helpers import copy_repo, snakemake

    checkout = tmp_path / "my check out"
    checkout.mkdir()
    copy_repo(checkout)
    (checkout / "workflow/config.yaml").write_bytes((tiny_built / "workflow/config.yaml").read_bytes())
    work, elsewhere = tmp_path / "work dir", tmp_path / "else where"
    elsewhere.mkdir()
    target = "results/tiny/N11/norms/L4.json"
    snakemake(elsewhere, "-c2", "-s", str(checkout / "Snakefile"), "-d", str(work), target, timeout=1800)
    assert load_json(work / target)["value"] == load_json(tiny_built / target)["value"]
    assert not (checkout / "results").exists() and not (elsewhere / "results").exists()


@pytest.mark.slow
def test_an_interpreter_in_a_path_the_shell_splits_is_refused_before_any_job(tmp_path):
    """Snakemake leaves the interpreter of script jobs unquoted: every job would fail with
    ``bash: .../sp: No such file or directory``; the workflow refuses at once and says why."""
    import sys

    from helpers import copy_repo

    repo = copy_repo(tmp_path)
    venv = tmp_path / "sp ace" / "venv"
    venv.parent.mkdir()
    venv.symlink_to(Path(sys.prefix))
    proc = subprocess.run(
        [str(venv / "bin/python"), "-m", "snakemake", "-n", "results/smoke/N11/solution.npz"],
        cwd=repo,
        capture_output=True,
        encoding="utf-8",
        timeout=600,
    )
    out = proc.stdout + proc.stderr  # Snakemake prints a Snakefile's error on stdout
    assert proc.returncode != 0 and "lies in a path the shell splits" in out and "make setup VENV=" in out
    assert not (repo / "results").exists()
