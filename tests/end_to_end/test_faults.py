"""Faults injected into the built repository copy that must never end in a wrong table with exit
code 0: code edited while jobs run, an input replaced under its consumers, damaged artifacts and
benchmark files, a run killed during a job, truncated artifacts.  Faults of the user's setting
(changed parameters and scenes, read-only calls, locale, working directory) are in
``test_setting_faults.py``; the faults one module catches on its own are tested with that module
(e.g. ``tests/pipeline/test_integrity.py``)."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import time

import numpy as np
import pytest
from helpers import clone_built, planned, snakemake

from signorini.pipeline.artifacts import load_json, load_npz
from signorini.pipeline.integrity import artifact_ok


@pytest.mark.slow
def test_an_edit_during_a_run_is_not_trusted(built_repo, tmp_path):
    """A norm job that imported the old code but finished after an edit leaves an artifact newer
    than the edit: modification times call it current, its recorded code digest does not."""
    from helpers import clone_built, planned, snakemake

    repo = clone_built(built_repo, tmp_path / "repo")
    module = repo / "src/signorini/fem/norms/conventional.py"
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
    assert "results/smoke/N21/solution.npz" in proc.stderr
    assert "was computed from another results/smoke/N21/system.npz than the one now on disk" in proc.stderr
    ran = planned(snakemake(repo, "-c2", "results/smoke/errors.csv"))
    assert ("solve", {"scene": "smoke", "N": "21"}) in ran and ("errors", {"scene": "smoke"}) in ran
    assert "discretise" not in {rule for rule, _ in ran}  # the replaced system is valid: it is used
    check_inputs(["results/smoke/N21/solution.npz"])


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
