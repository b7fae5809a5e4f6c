"""Faults of the user's setting, on a small built copy of the workflow (``tiny_built``), that must
never end in a wrong table with exit code 0: changed parameters and scenes without Snakemake's
metadata, read-only calls in every spelling, a non-UTF-8 locale, other working directories, paths
with spaces and an interpreter in a path the shell splits.  This module needs no built copy of the
whole workflow (``conftest.built_repo``), so it runs while that copy is being built."""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import PROBLEM, clone_built, snakemake

from signorini.pipeline.artifacts import load_json

@pytest.fixture(scope="module")
def tiny_built(tmp_path_factory):
    """A repository copy whose rendered scene is ``tiny`` (the smoke scene on N = 11, 21: every norm
    the paper's outputs need), with ``all`` built: the small workflow the fault tests below damage."""
    from helpers import copy_repo

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

    from helpers import SNAKEMAKE

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
    from helpers import copy_repo

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
