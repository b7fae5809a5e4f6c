"""Faults injected into repository copies that must never end in a wrong table with exit code 0:
code edited while jobs run, an input replaced under its consumers, damaged artifacts and benchmark
files, a run killed during a job, changed parameters and scenes without Snakemake's metadata,
read-only calls in every spelling, a non-UTF-8 locale, other working directories and paths with
spaces.  The faults one module catches on its own are tested with that module (e.g.
``tests/pipeline/test_integrity.py``)."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import PROBLEM, clone_built, planned, snakemake

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
    assert "results/tiny/N11/system.npz" in proc.stderr and "other parameters" in proc.stderr
    assert "a run moves them to <name>.stale" in proc.stderr and errors.read_text() == before.text
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
        assert "results/tiny/errors.csv" in out.stderr and "other parameters" in out.stderr
        assert "moved to <name>.stale" in out.stderr and "corrupt" not in out.stderr
    assert not list((repo / "results").rglob("*.corrupt"))
    assert (repo / "results/tiny/errors.csv.stale").exists()  # moved aside, never deleted


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
    assert "paper_figures/table1.csv" in proc.stderr and "(rendered anew)" in proc.stderr
    table1 = read_errors_csv(repo / "paper_figures/table1.csv")
    table2 = read_errors_csv(repo / "paper_figures/table2.csv")
    assert list(table1.rows) == ["1/11", "1/21", "1/31"] and list(table2.rows) == ["1/21", "1/31", "regr.", "theo."]
    assert "1/31" in (repo / "paper_figures/reproduction.md").read_text(encoding="utf-8")


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
    module = repo / "src/signorini/fem/norms/conventional.py"
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
            assert "computed by other code" in proc.stderr, (args, proc.stderr[-3000:])
            assert "a run moves them to <name>.stale" in proc.stderr, (args, proc.stderr[-3000:])
            assert f"{damaged.relative_to(repo)}: damaged" in proc.stderr, args


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
