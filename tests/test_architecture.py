"""The architecture: the layers' import boundaries, the code dependencies derived from the
imports (``signorini.pipeline.codedeps``), and what an edit of each module re-runs.

The edit matrix appends a comment to each module under ``src/signorini/`` in turn, in a copy
of the built repository (``conftest.built_repo``), and checks with a dry run that exactly the
jobs whose stage imports the module (directly or indirectly), and the jobs downstream of
them, are planned.  The dry runs happen in one interpreter (``snakemake.cli.main`` called in
a loop), so the matrix costs a fraction of a second per module.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from conftest import BUILT_TARGETS
from helpers import ROOT, clone_built, dry_run_jobs, job_key

from signorini.pipeline.codedeps import ImportCache, _imports, _module_file, _module_name, import_closure

SRC = ROOT / "src"
PACKAGE = SRC / "signorini"
AGGREGATES = {"all", "theory", "work_precision", "stability", "true_norms"}  # target rules without a script


# --- layers ------------------------------------------------------------------------------------


def imported_names(path: Path) -> set[str]:
    module = ".".join(path.relative_to(SRC).with_suffix("").parts)
    return set(_imports(ast.parse(path.read_text()), module, path.name == "__init__.py"))


@pytest.mark.parametrize("layer", ["fem", "solvers"])
def test_the_mathematics_imports_no_study_plotting_io_or_tables(layer):
    """fem/ and solvers/ import nothing from the studies, the plotting, the workflow
    infrastructure, pandas or matplotlib (not even inside a function)."""
    banned = ("signorini.studies", "signorini.plotting", "signorini.pipeline", "signorini.explore", "pandas",
              "matplotlib")
    for path in sorted((PACKAGE / layer).rglob("*.py")):
        bad = sorted(n for n in imported_names(path) if n.startswith(banned))
        assert not bad, f"{path.relative_to(ROOT)} imports {bad}"


def import_graph(src: Path = SRC) -> dict[str, set[str]]:
    """{module: the package modules it imports}, at module level or inside a function (not under
    ``TYPE_CHECKING``: those never run); ``from a import b`` counts as importing ``a.b`` when that
    is a module, else ``a``."""
    graph = {}
    for path in sorted((src / "signorini").rglob("*.py")):
        module = _module_name(path, src)
        names = {n for n in _imports(ast.parse(path.read_text(encoding="utf-8")), module, path.name == "__init__.py")
                 if _module_file(n, src) is not None}
        graph[module] = {n for n in names if not any(m.startswith(n + ".") for m in names)} - {module}
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan's algorithm, iterative)."""
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    cycles.append(sorted(component))
    return cycles


def test_no_import_cycles_in_the_package():
    """No module of ``src/`` imports itself through others, not even inside a function."""
    graph = import_graph()
    assert "signorini.fem.conventions" in graph["signorini.fem.p1norms"]  # the graph sees imports
    assert import_cycles(graph) == []


def test_the_cycle_finder_finds_function_level_and_longer_cycles(tmp_path):
    src = tmp_path / "src"
    files = {
        "signorini/__init__.py": "",
        "signorini/a.py": "def f():\n    from signorini import b\n",  # a -> b, inside a function
        "signorini/b.py": "from signorini.c import x\n",  # b -> c
        "signorini/c.py": "import signorini.a\nx = 1\n",  # c -> a: the circle a -> b -> c -> a
        "signorini/d.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from signorini import e\n",
        "signorini/e.py": "from signorini import d\n",  # d -> e only for type checkers: no cycle
    }
    for rel, text in files.items():
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text(text, encoding="utf-8")
    graph = import_graph(src)
    assert graph["signorini.a"] == {"signorini.b"} and graph["signorini.d"] == set()
    assert import_cycles(graph) == [["signorini.a", "signorini.b", "signorini.c"]]


def test_package_inits_import_nothing():
    """Importing one module runs only that module's imports (and the empty package inits)."""
    for path in sorted(PACKAGE.rglob("__init__.py")):
        if path.parent.name == "solvers":  # the solvers' public interface, one unit
            continue
        # the top-level init may set the jobs' Ctrl-C handler (stdlib os and signal only)
        allowed = {"os", "signal"} if path == PACKAGE / "__init__.py" else set()
        assert not imported_names(path) - allowed, f"{path.relative_to(ROOT)} imports something"


def test_no_function_longer_than_80_lines():
    """Anywhere in the package, the benchmarks, the workflow's scripts and the peers' driver; no
    exemptions."""
    long = []
    trees = (PACKAGE, ROOT / "benchmarks", ROOT / "workflow", ROOT / "scripts")
    for path in sorted(p for tree in trees for p in tree.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > 80:
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} ({length} lines)")
    assert not long, long


# --- the import closure --------------------------------------------------------------------------


def test_import_closure_follows_every_kind_of_import(tmp_path):
    src = tmp_path / "src"
    files = {
        "signorini/__init__.py": "",
        "signorini/a/__init__.py": "",
        "signorini/a/top.py": "from signorini.a import lazy_user\nimport signorini.b.deep as d\n",
        "signorini/a/lazy_user.py": "def f():\n    from . import sibling\n",
        "signorini/a/sibling.py": "from ..c import thing\n",
        "signorini/b/__init__.py": "",
        "signorini/b/deep.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import signorini.never\n",
        "signorini/c.py": "thing = 1\n",
        "signorini/never.py": "",
        "signorini/unused.py": "",
    }
    for rel, text in files.items():
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text(text)
    script = tmp_path / "script.py"
    script.write_text("import numpy\nfrom signorini.a.top import x\n")
    found = {p.relative_to(src).as_posix() for p in import_closure(script, src)}
    assert found == {
        "signorini/__init__.py",
        "signorini/a/__init__.py",
        "signorini/a/top.py",
        "signorini/a/lazy_user.py",  # ``from package import module``
        "signorini/a/sibling.py",  # relative import inside a function
        "signorini/b/__init__.py",
        "signorini/b/deep.py",  # ``import a.b as c``
        "signorini/c.py",  # ``from ..c import name``
    }


def test_the_import_cache_holds_only_while_a_file_is_unchanged(tmp_path):
    """Direct imports come from the cache file in another process, until the file's content changes
    (even with its size and modification time kept)."""
    src = tmp_path / "src"
    (src / "signorini").mkdir(parents=True)
    for name, text in {"__init__.py": "", "a.py": "", "b.py": "", "c.py": ""}.items():
        (src / "signorini" / name).write_text(text)
    script, cache_file = tmp_path / "script.py", tmp_path / "cache/imports.json"
    script.write_text("from signorini import a\n")

    def closure() -> set[str]:
        cache = ImportCache(cache_file)  # a new process
        found = {p.name for p in import_closure(script, src, cache)}
        cache.save()
        assert found == {p.name for p in import_closure(script, src)}  # the same as without a cache
        return found

    assert closure() == {"__init__.py", "a.py"}
    entries = json.loads(cache_file.read_text())
    assert len(entries) == 3  # the script, signorini/__init__.py, a.py
    (src / "signorini/a.py").write_text("from signorini import b\n")  # a new import, new size
    assert closure() == {"__init__.py", "a.py", "b.py"}
    stat = (src / "signorini/a.py").stat()
    (src / "signorini/a.py").write_text("from signorini import c\n")  # same size, same time
    os.utime(src / "signorini/a.py", ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert closure() == {"__init__.py", "a.py", "c.py"}
    cache_file.write_text("{truncated")  # a damaged cache is an empty one
    assert closure() == {"__init__.py", "a.py", "c.py"}
    assert json.loads(cache_file.read_text())


def test_every_rule_with_a_script_lists_its_closure(tmp_path):
    """The Snakefile lists the closure as a rule's code input: the solve job of a dry run."""
    from helpers import copy_repo, snakemake

    copy_repo(tmp_path)
    text = snakemake(tmp_path, "-n", "--forceall", "results/smoke/N11/solution.npz").stdout
    (solve,) = [job for job in dry_run_jobs(text) if job["rule"] == "solve"]
    listed = {p for p in solve["input"] if p.startswith(("src/", "workflow/scripts/"))}
    closure = import_closure(tmp_path / "workflow/scripts/solve.py", tmp_path / "src")
    assert listed == {"workflow/scripts/solve.py"} | {p.relative_to(tmp_path).as_posix() for p in closure}
    assert "src/signorini/solvers/active_set.py" in listed and "src/signorini/fem/norms.py" not in listed


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
    out = {"": dry(["--forceall", *targets]), "unchanged": dry(targets)}
    for rel in modules:
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


@pytest.fixture(scope="module")
def edit_matrix(built_repo, tmp_path_factory):
    """{module: planned jobs after its edit}, the whole DAG (``""``) and the repository copy."""
    repo = clone_built(built_repo, tmp_path_factory.mktemp("matrix"))
    modules = sorted(p.relative_to(repo).as_posix() for p in (repo / "src/signorini").rglob("*.py"))
    proc = subprocess.run(
        [sys.executable, "-c", DRIVER, json.dumps(BUILT_TARGETS), json.dumps(modules)],
        cwd=repo,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-5000:]
    runs = json.loads(proc.stdout.strip().splitlines()[-1])
    return repo, {key: dry_run_jobs(text) for key, text in runs.items()}


def expected_after_edit(repo: Path, dag: list[dict], module: str) -> set:
    """The jobs whose script imports ``module`` (directly or not), and every job downstream."""
    code = {}
    for rule in {job["rule"] for job in dag} - AGGREGATES:
        script = repo / "workflow/scripts" / f"{rule}.py"
        code[rule] = {p.relative_to(repo).as_posix() for p in import_closure(script, repo / "src")}
    producer = {path: job_key(job) for job in dag for path in job["output"]}
    parents = {job_key(job): {producer[p] for p in job["input"] if p in producer} for job in dag}
    rerun = {job_key(job) for job in dag if module in code.get(job["rule"], ())}
    changed = True
    while changed:
        grown = rerun | {key for key, ups in parents.items() if ups & rerun}
        changed, rerun = grown != rerun, grown
    return rerun


@pytest.mark.slow
def test_edit_matrix_plans_exactly_the_importing_jobs(edit_matrix):
    repo, runs = edit_matrix
    dag = runs[""]
    assert runs["unchanged"] == [], "the built copy is not up to date"
    wrong = {}
    for module, jobs in runs.items():
        if module in ("", "unchanged"):
            continue
        got, want = {job_key(job) for job in jobs}, expected_after_edit(repo, dag, module)
        if got != want:
            wrong[module] = {"unexpected": sorted(got - want)[:5], "missing": sorted(want - got)[:5]}
    assert not wrong, json.dumps(wrong, indent=1)


def rules_after(runs: dict, module: str) -> set[str]:
    return {job["rule"] for job in runs[f"src/signorini/{module}"]} - AGGREGATES


@pytest.mark.slow
def test_edits_rerun_what_the_design_promises(edit_matrix):
    _, runs = edit_matrix
    figures = {"figure2", "figure3", "theory_report", "work_precision_figures", "stability_atlas"}
    assert rules_after(runs, "plotting.py") == figures  # every figure of every study, nothing else
    assert rules_after(runs, "studies/paper/runtime.py") == {"runtime"}  # no solve, no norm
    paper = {"discretise", "solve", "norm", "errors", "eoc", "sample", "table1", "table2", "figure2", "figure3",
             "reproduction", "runtime"}
    for renderer in ("report.py", "findings.py", "figures.py", "table.py"):
        rules = rules_after(runs, f"studies/work_precision/{renderer}")
        assert rules and rules <= {"work_precision_table", "work_precision_figures", "work_precision_report"}
        assert not rules & paper
    assert rules_after(runs, "studies/paper/tables.py") == {"table1", "table2", "reproduction"}
    norms = rules_after(runs, "fem/norms.py")
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
        script = repo / "workflow/scripts" / f"{job['rule']}.py"
        declared = {
            ".".join(p.relative_to(repo / "src").with_suffix("").parts).removesuffix(".__init__")
            for p in import_closure(script, repo / "src")
        }
        assert set(loaded) <= declared, f"{job['rule']} ran undeclared {sorted(set(loaded) - declared)}"
        checked += 1
    assert checked > 50


def test_the_package_version_is_the_project_version():
    import tomllib

    import signorini

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert signorini.__version__ == project["version"]


def test_citation_names_this_version_and_the_paper():
    import yaml

    import signorini

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and str(cff["version"]) == signorini.__version__
    (paper,) = cff["references"]
    assert paper["doi"].startswith("10.1007/s00211") and paper["journal"] == "Numerische Mathematik"
    assert cff["license"] in (ROOT / "LICENSE").read_text().replace("BSD 3-Clause", "BSD-3-Clause")


def test_the_thread_variables_are_named_in_one_module():
    """The environment a job computes in is set in one place (``signorini.pipeline.jobenv``):
    no other file of the tree names a thread variable."""
    from signorini.pipeline.jobenv import THREAD_VARIABLES

    files = [ROOT / "Snakefile", *(p for d in ("src", "workflow", "benchmarks", "tests", "notebooks")
                                   for p in (ROOT / d).rglob("*") if p.suffix in (".py", ".smk"))]
    naming = {
        str(p.relative_to(ROOT))
        for p in files
        if any(name in p.read_text(encoding="utf-8") for name in THREAD_VARIABLES)
    }
    assert naming == {"src/signorini/pipeline/jobenv.py"}
