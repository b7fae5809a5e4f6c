"""The rules' code inputs on repository copies: each rule lists the import closure of its script
(``signorini.pipeline.codedeps``), and an edit of a module re-runs exactly the jobs that import it.

The edit matrix, in a copy of the built repository (``conftest.built_repo``): every job of the whole
DAG lists its script's import closure, and appending a comment to a module plans, in a dry run,
exactly the jobs whose stage imports the module (directly or indirectly) and the jobs downstream of
them.  The edits are made for modules of every reach (and the modules the design test names); the dry
runs happen in one interpreter (``snakemake.cli.main`` called in a loop)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from helpers import BUILT_TARGETS, clone_built, dry_run_jobs, job_key

from signorini.pipeline.codedeps import import_closure
from signorini.pipeline.paths import TARGETS

AGGREGATES = set(TARGETS)  # the target rules, which have no script


def test_every_rule_with_a_script_lists_its_closure(tmp_path):
    """The Snakefile lists the closure as a rule's code input: the solve job of a dry run."""
    from helpers import copy_repo, snakemake

    copy_repo(tmp_path)
    text = snakemake(tmp_path, "-n", "--forceall", "results/smoke/N11/solution.npz").stdout
    (solve,) = [job for job in dry_run_jobs(text) if job["rule"] == "solve"]
    listed = {p for p in solve["input"] if p.startswith(("src/", "workflow/scripts/"))}
    closure = import_closure(tmp_path / "workflow/scripts/solve.py", tmp_path / "src")
    assert listed == {"workflow/scripts/solve.py"} | {p.relative_to(tmp_path).as_posix() for p in closure}
    assert "src/signorini/solvers/active_set.py" in listed and "src/signorini/fem/norms/conventional.py" not in listed


# --- the edit matrix ---------------------------------------------------------------------------

DRIVER = textwrap.dedent(
    r"""
    import contextlib, io, json, os, sys, time
    from pathlib import Path
    from snakemake.cli import main

    def dry(args):
        sys.argv = ["snakemake", "-n", *args]  # what the Snakefile sees (a dry run: read-only)
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
            try:
                main(["-n", *args])
            except SystemExit as exit:
                if exit.code:
                    raise RuntimeError(buf.getvalue()[-3000:])
        return buf.getvalue()

    targets, modules = json.loads(sys.argv[1]), json.loads(sys.argv[2])
    out = {"": dry(["--forceall", *targets]), "unchanged": dry(targets)} if modules is None else {}
    for rel in modules or ():
        path = Path(rel)
        text, st = path.read_text(), path.stat()
        try:
            path.write_text(text + "\n# an edit\n")
            future = time.time() + 5
            os.utime(path, (future, future))
            out[rel] = dry(targets)
        finally:
            path.write_text(text)
            os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns))
    print(json.dumps(out))
    """
)
# the modules whose edits the design test below names: always among the edited ones
NAMED = (
    "plotting.py",
    "studies/paper/runtime.py",
    "studies/paper/tables.py",
    "fem/norms/conventional.py",
    "solvers/active_set.py",
    *(f"studies/work_precision/{m}" for m in ("report.py", "findings.py", "figures.py", "table.py")),
)


def dry_runs(repo: Path, modules: list[str] | None) -> dict[str, list[dict]]:
    """The dry runs of the built targets in ``repo``: after an edit of each of ``modules``, or (None)
    the whole DAG (``""``) and the unchanged copy (``"unchanged"``), in one interpreter."""
    proc = subprocess.run(
        [sys.executable, "-c", DRIVER, json.dumps(BUILT_TARGETS), json.dumps(modules)],
        cwd=repo,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-5000:]
    return {key: dry_run_jobs(text) for key, text in json.loads(proc.stdout.strip().splitlines()[-1]).items()}


@pytest.fixture(scope="module")
def edit_matrix(built_repo, tmp_path_factory):
    """{module: planned jobs after its edit}, the whole DAG (``""``) and the repository copy.

    Every module is checked through the code inputs the DAG declares (``test_every_job_lists_its_closure``):
    an edit of it is newer than the outputs of exactly the jobs that import it, and Snakemake plans a job
    when any of its inputs is newer than its outputs.  What is left to check is that the plan follows
    (downstream jobs included, the cache check not interfering), for edits of every reach: the modules
    ``NAMED``, and the first module of the smallest, the largest and three intermediate sets of jobs
    an edit must rerun."""
    repo = clone_built(built_repo, tmp_path_factory.mktemp("matrix"))
    runs = dry_runs(repo, None)
    modules = sorted(p.relative_to(repo).as_posix() for p in (repo / "src/signorini").rglob("*.py"))
    first: dict[frozenset, str] = {}
    code = closures(repo, runs[""])
    for module in modules:
        first.setdefault(frozenset(expected_after_edit(runs[""], module, code)), module)
    by_reach = [first[jobs] for jobs in sorted(first, key=lambda jobs: (len(jobs), first[jobs]))]
    spread = {by_reach[round(q * (len(by_reach) - 1))] for q in (0, 0.25, 0.5, 0.75, 1)}
    edited = sorted(spread | {f"src/signorini/{m}" for m in NAMED})
    return repo, runs | dry_runs(repo, edited)


def script_of(repo: Path, job: dict) -> Path:
    """A job's script: the one of ``workflow/scripts/`` among its inputs (a scene's per-mesh norms rule
    runs norm.py, the finest scene's tables fine_tables.py)."""
    (script,) = [p for p in job["input"] if p.startswith("workflow/scripts/")]
    return repo / script


def closures(repo: Path, dag: list[dict]) -> dict[str, set[str]]:
    """The import closure of each rule's script, relative to ``repo``."""
    scripts = {job["rule"]: script_of(repo, job) for job in dag if job["rule"] not in AGGREGATES}
    return {
        rule: {p.relative_to(repo).as_posix() for p in import_closure(script, repo / "src")}
        for rule, script in scripts.items()
    }


def expected_after_edit(dag: list[dict], module: str, code: dict[str, set[str]]) -> set:
    """The jobs whose script imports ``module`` (directly or not: ``code``, the ``closures``), and every
    job downstream."""
    producer = {path: job_key(job) for job in dag for path in job["output"]}
    parents = {job_key(job): {producer[p] for p in job["input"] if p in producer} for job in dag}
    rerun = {job_key(job) for job in dag if module in code.get(job["rule"], ())}
    changed = True
    while changed:
        grown = rerun | {key for key, ups in parents.items() if ups & rerun}
        changed, rerun = grown != rerun, grown
    return rerun


@pytest.mark.slow
def test_every_job_lists_its_closure(edit_matrix):
    """Every job of the whole DAG lists as code inputs exactly the package modules its script imports
    (directly or not): an edit of any module is newer than the outputs of exactly the jobs that
    import it."""
    repo, runs = edit_matrix
    code = closures(repo, runs[""])
    wrong = {}
    for job in runs[""]:
        if job["rule"] in AGGREGATES:
            continue
        # the package modules (a rule may list a data file of the package beside them: a template)
        listed = {p for p in job["input"] if p.startswith("src/") and p.endswith(".py")}
        closure = code[job["rule"]]
        if listed != closure:
            wrong[job["rule"]] = {"unlisted": sorted(closure - listed), "extra": sorted(listed - closure)}
    assert not wrong, json.dumps(wrong, indent=1)


@pytest.mark.slow
def test_edit_matrix_plans_exactly_the_importing_jobs(edit_matrix):
    repo, runs = edit_matrix
    dag, code = runs[""], closures(repo, runs[""])
    assert runs["unchanged"] == [], "the built copy is not up to date"
    wrong = {}
    for module, jobs in runs.items():
        if module in ("", "unchanged"):
            continue
        got, want = {job_key(job) for job in jobs}, expected_after_edit(dag, module, code)
        if got != want:
            wrong[module] = {"unexpected": sorted(got - want)[:5], "missing": sorted(want - got)[:5]}
    assert not wrong, json.dumps(wrong, indent=1)


def rules_after(runs: dict, module: str) -> set[str]:
    return {job["rule"] for job in runs[f"src/signorini/{module}"]} - AGGREGATES


@pytest.mark.slow
def test_edits_rerun_what_the_design_promises(edit_matrix):
    _, runs = edit_matrix
    figures = {"figure2", "figure3", "theory_report", "work_precision_figures", "stability_atlas", "contact_set",
               "free_point_error", "eoc_against_h", "meshes_report"}
    # every figure of every study, and the summary, which reads the contact verdicts from the module
    # whose stage also draws contact_set (the static closure counts that stage's imports)
    assert rules_after(runs, "plotting.py") == figures | {"summary"}
    assert rules_after(runs, "studies/paper/runtime.py") == {"runtime"}  # no solve, no norm
    paper = {"discretise", "solve", "norm", "errors", "eoc", "sample", "table1", "table2", "figure2", "figure3",
             "reproduction", "runtime"}
    for renderer in ("report.py", "findings.py", "figures.py", "table.py"):
        rules = rules_after(runs, f"studies/work_precision/{renderer}")
        # and the summary, which states the study's race through its findings
        assert rules and rules <= {"work_precision_table", "work_precision_figures", "work_precision_report", "summary"}
        assert not rules & paper
    # and what reads the tables: the reproduction report and the summary
    assert rules_after(runs, "studies/paper/tables.py") == {"table1", "table2", "reproduction", "summary"}
    norms = rules_after(runs, "fem/norms/conventional.py")
    assert "norm" in norms and not norms & {"discretise", "solve", "sample", "figure2"}
    solver = rules_after(runs, "solvers/active_set.py")
    assert {"solve", "norm", "errors", "eoc", "table1", "runtime"} <= solver and "discretise" not in solver


@pytest.mark.slow
def test_jobs_ran_only_modules_they_declare(edit_matrix):
    """Soundness of the static closure: the package modules each job of the built copy really
    loaded (the last line of its log) are among the rule's code inputs."""
    repo, runs = edit_matrix
    checked = 0
    for job in runs[""]:
        if job["rule"] in AGGREGATES or not job["log"]:
            continue
        lines = [ln for ln in (repo / job["log"][0]).read_text().splitlines() if "modules run:" in ln]
        assert lines, f"{job['log'][0]}: no modules line"
        loaded = lines[-1].split("modules run: ", 1)[1].split()
        script = script_of(repo, job)
        declared = {
            ".".join(p.relative_to(repo / "src").with_suffix("").parts).removesuffix(".__init__")
            for p in import_closure(script, repo / "src")
        }
        assert set(loaded) <= declared, f"{job['rule']} ran undeclared {sorted(set(loaded) - declared)}"
        checked += 1
    assert checked > 50
