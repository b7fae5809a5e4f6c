"""Faults that must never end in a wrong table with exit code 0: non-finite or negative norm
values, tables that lost a row, a scene whose errors vanish, artifacts unreadable by others."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import time

import numpy as np
import pytest
import yaml
from helpers import PROBLEM, ROOT

from signorini.pipeline.artifacts import CorruptArtifactError, load_json, save_json
from signorini.pipeline.cache import artifact_ok, cached_artifacts, corrupt_artifacts, quarantine_corrupt
from signorini.pipeline.config import ConfigError, check_config
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
    monkeypatch.setattr(stage, "evaluate_norms", lambda *args, **kwargs: {"L4": bad})
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
def test_a_table_that_lost_a_row_is_caught(tmp_path, table, text):
    scene = {"N": [11, 21, 41]}
    path = tmp_path / "s" / table
    path.parent.mkdir()
    path.write_text(text)
    assert not corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene}))
    lines = text.splitlines(keepends=True)
    path.write_text("".join(lines[:2] + lines[3:]))  # sed -i '3d': a complete-looking table without one N
    assert artifact_ok(path)  # every row is well formed ...
    assert corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene})) == [str(path)]  # ... but an N is missing
    assert quarantine_corrupt(cached_artifacts(tmp_path, {"s": scene})) == [str(path)]
    assert (tmp_path / "s" / f"{table}.corrupt").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-0.5"])
def test_a_table_with_a_non_finite_or_negative_error_is_caught(tmp_path, value):
    path = tmp_path / "errors.csv"
    path.write_text(ERRORS.replace("0.012", value))
    assert not artifact_ok(path, ["11", "21", "41"])


def test_a_vanishing_error_or_a_single_mesh_stops_the_eoc_job(tmp_path):
    (tmp_path / "errors.csv").write_text(ERRORS.replace("0.012", "0.0"))
    with pytest.raises(ValueError, match="L4 error vanishes"):
        eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    (tmp_path / "errors.csv").write_text("N,h,L4\n11,0.0909,0.04\n")
    with pytest.raises(ValueError, match="at least two meshes"):
        eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    assert not (tmp_path / "eoc.csv").exists()


def test_a_scene_whose_errors_vanish_is_rejected():
    config = yaml.safe_load((ROOT / "workflow/config.yaml").read_text())
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
    config = yaml.safe_load((ROOT / "workflow/config.yaml").read_text())
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
    config = yaml.safe_load((ROOT / "workflow/config.yaml").read_text())
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
    config = yaml.safe_load((ROOT / "workflow/config.yaml").read_text())
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
    from signorini.pipeline.cache import leftover_temporaries, remove_leftover_temporaries

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
