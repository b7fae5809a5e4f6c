"""The architecture: the layers' import boundaries, no import cycles, package inits that import
nothing, no function over 80 lines, text I/O that names its encoding, no measurement recorded in a
comment (its figures live in docs/evidence/design-measurements.md), and the tests' layout (every
module of ``src/`` has its test module where docs/architecture.md says)."""

from __future__ import annotations

import ast
import functools
import io
import re
import tokenize
import warnings
from pathlib import Path

import pytest
from helpers import ROOT

from signorini.pipeline.codedeps import _imports, _module_file, _module_name

SRC = ROOT / "src"
PACKAGE = SRC / "signorini"


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


def test_the_workflow_infrastructure_imports_no_study():
    """pipeline/ stands below the studies: it imports none of them, nor the plotting, the
    notebooks' helpers or the command line (not even inside a function)."""
    banned = ("signorini.studies", "signorini.plotting", "signorini.explore", "signorini.cli")
    for path in sorted((PACKAGE / "pipeline").rglob("*.py")):
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
    assert "signorini.fem.norms.conventions" in graph["signorini.fem.norms.p1"]  # the graph sees imports
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
        if name == "open" and owner == "archive":  # a zipfile.ZipFile's member: bytes, by the name's convention
            continue
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


# --- measurements live in docs/evidence/, not in comments ------------------------------------------

# A comment that reports a measurement dates with the machine and the code: the comment gives the
# reason for a choice and points to docs/evidence/design-measurements.md, which holds the figures.
# Caught: "measured" followed, in the same sentence of one comment (comment lines of their own on
# consecutive lines are one) or of one docstring paragraph, by a time, a memory size, a share or a ratio.
_MEASURED = re.compile(r"\bmeasured\b", re.I)
_FIGURE = re.compile(
    r"\d+(?:\.\d+)?\s*(?:s|ms|µs|GiB|GB|MB|MiB|%)(?!\w)"  # a time, a memory size, a share
    r"|×\s*\d|\d\s*[x×](?!\w)"  # a ratio: ×1.6, 200x
    r"|\d+(?:\.\d+)?\s+times\b"  # 1.06 times the bound
)
_SENTENCE_END = re.compile(r"[.!?](?=\s+[A-Z0-9*(`'\"])")
DESIGN_MEASUREMENTS = ROOT / "docs" / "evidence" / "design-measurements.md"
# Hits left for later, as (file under src/signorini/, the line's text stripped): only in
# studies/work_precision/, which is being rewritten.  The test reports each one still there (a
# warning) and fails on one that is gone (take it off the list).  None at present.
MEASUREMENTS_LEFT: set[tuple[str, str]] = set()


def _comment_blocks(source: str) -> list[tuple[int, str]]:
    """(first line, text without the ``#``) of every comment; a comment on a line of its own right
    after another comment continues it if that one is on a line of its own too, or starts in the
    same column (a trailing comment's continuation)."""
    blocks: list[list] = []
    previous = None  # (row, column, on a line of its own) of the last comment
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type != tokenize.COMMENT:
            continue
        (row, column), alone = tok.start, not tok.line[: tok.start[1]].strip()
        if alone and previous and previous[0] == row - 1 and (previous[2] or previous[1] == column):
            blocks[-1][1] += "\n" + tok.string.lstrip("#")
        else:
            blocks.append([row, tok.string.lstrip("#")])
        previous = (row, column, alone)
    return [(row, text) for row, text in blocks]


def _docstring_paragraphs(source: str) -> list[tuple[int, str]]:
    """(first line, text) of every paragraph (lines between blank ones) of every docstring."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        doc = ast.get_docstring(node, clean=False)
        if doc is None:
            continue
        first, paragraph = node.body[0].lineno, []
        for i, line in enumerate([*doc.split("\n"), ""]):
            if line.strip():
                paragraph.append((i, line))
            elif paragraph:
                found.append((first + paragraph[0][0], "\n".join(text for _, text in paragraph)))
                paragraph = []
    return found


def measurement_phrases(source: str) -> list[tuple[int, str]]:
    """(line, that line's text) of every "measured" in a comment or docstring of ``source`` that a
    figure (``_FIGURE``) follows in the same sentence."""
    found = set()
    for row, text in _comment_blocks(source) + _docstring_paragraphs(source):
        for match in _MEASURED.finditer(text):
            end = _SENTENCE_END.search(text, match.end())
            if _FIGURE.search(text, match.end(), end.start() if end else len(text)):
                k = text.count("\n", 0, match.start())
                found.add((row + k, text.split("\n")[k].strip()))
    return sorted(found)


_MEASURING_SOURCE = '''\
"""A module.

The routes were measured side by side: ×1.6 at N = 401.
Nothing measured here has a figure after it. It took 3 s.
"""
X = 1  # measured: 200x below the estimate
# the crossover, measured on one thread
# at N = 201 to 451 (CPU seconds: 2.5 s against 3.1 s)
Y = 2  # a tolerance of 1e-14 s, not measured
Z = "measured: 3 s"  # a string of the code, not a comment


def f():
    """The peaks measured at N = 2001: 7.3 GiB.

    The measured system's own matrix.  Its calls take 0.1 s."""
'''


def test_the_measurement_check_finds_what_it_should():
    found = measurement_phrases(_MEASURING_SOURCE)
    assert [line for line, _ in found] == [3, 6, 7, 14]
    assert found[1] == (6, "measured: 200x below the estimate")
    # each hit goes with its figure: without it, or with the figure in the next sentence, no hit
    assert 3 not in dict(measurement_phrases(_MEASURING_SOURCE.replace("×1.6", "ahead")))
    assert 6 not in dict(measurement_phrases(_MEASURING_SOURCE.replace("200x", "far")))
    assert 7 not in dict(measurement_phrases(_MEASURING_SOURCE.replace("2.5 s against 3.1 s", "ours first")))
    assert 14 not in dict(measurement_phrases(_MEASURING_SOURCE.replace(": 7.3 GiB.", ". It took 7.3 GiB.")))
    # and a figure after "measured" in the sentence that had none is found, in a trailing comment's
    # continuation too
    assert 4 in dict(measurement_phrases(_MEASURING_SOURCE.replace("after it. It", "after it: it")))
    continued = _MEASURING_SOURCE.replace("estimate\n", "estimate\n       # at 3 s\n").replace("200x", "far")
    assert 6 in dict(measurement_phrases(continued))


def test_no_comment_records_a_measurement():
    """Comments and docstrings of src/signorini/ give the reason for a choice and point to
    docs/evidence/design-measurements.md for its figures.  Hits on ``MEASUREMENTS_LEFT`` are
    reported as warnings, so that they can be cleaned later."""
    hits = {
        (str(path.relative_to(PACKAGE)), line, text)
        for path in sorted(PACKAGE.rglob("*.py"))
        for line, text in measurement_phrases(path.read_text(encoding="utf-8"))
    }
    assert all(file.startswith("studies/work_precision/") for file, _ in MEASUREMENTS_LEFT)
    for file, line, text in sorted(hits):
        if (file, text) in MEASUREMENTS_LEFT:
            warnings.warn(f"a measurement still in a comment: src/signorini/{file}:{line}: {text}", stacklevel=1)
    gone = MEASUREMENTS_LEFT - {(file, text) for file, _, text in hits}
    assert not gone, f"on MEASUREMENTS_LEFT but no longer in the code (take them off): {sorted(gone)}"
    new = [f"src/signorini/{f}:{line}: {text}" for f, line, text in sorted(hits) if (f, text) not in MEASUREMENTS_LEFT]
    assert not new, "measurements in comments (their figures belong in docs/evidence/design-measurements.md):\n" + (
        "\n".join(new)
    )


def test_the_code_and_the_design_measurements_point_to_each_other():
    """Every ``design-measurements.md#section`` the code names is a section of the page, and every
    section of the page is named by the code (a section no code points to justifies nothing)."""
    sections = set(re.findall(r"^## ([a-z0-9-]+)\s*$", DESIGN_MEASUREMENTS.read_text(encoding="utf-8"), re.M))
    pointers = {
        (str(path.relative_to(ROOT)), section)
        for path in sorted(PACKAGE.rglob("*.py"))
        for section in re.findall(r"design-measurements\.md#([\w-]+)", path.read_text(encoding="utf-8"))
    }
    assert sections and pointers, "no section or no pointer found: the check is blind"
    assert not sorted(p for p in pointers if p[1] not in sections), "pointers to no section"
    assert not sections - {section for _, section in pointers}, "sections no code points to"


# --- the tests' layout ------------------------------------------------------------------------------

# tests/ mirrors src/signorini/ (docs/architecture.md): the module signorini.<a>.<b> is tested in
# tests/<a>/test_<b>.py, a package whose __init__ holds code in test_<package>.py inside its folder
# (signorini.solvers: tests/solvers/test_solvers.py; signorini itself: tests/test_signorini.py),
# another top-level package of src/ (the logger plugin) in tests/test_<package>.py, a script of
# benchmarks/ that others import (benchmarks/race.py) in tests/benchmarks/test_<script>.py.  Modules
# listed here, with the reason, need no test module of their own.
LAYOUT_EXEMPT: dict[str, str] = {}
# test modules at the top of tests/ that check the repository, not one module
REPOSITORY_CHECKS = ("test_architecture.py", "test_docs.py", "test_setup.py", "test_figures_not_clipped.py")
END_TO_END = "end_to_end"  # tests/end_to_end/: Snakemake runs on repository copies, by theme
BENCHMARKS = "benchmarks"  # tests/benchmarks/test_<script>.py: the tests of benchmarks/<script>.py


def holds_code(path: Path) -> bool:
    """A module, or a package ``__init__`` with more than a docstring and ``from __future__`` imports."""
    if path.name != "__init__.py":
        return True
    body = ast.parse(path.read_text(encoding="utf-8")).body
    docstring = [n for n in body[:1] if isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)]
    future = [n for n in body if isinstance(n, ast.ImportFrom) and n.module == "__future__"]
    return len(body) > len(docstring) + len(future)


def layout_test_module(module: str, package: bool) -> Path:
    """Where the layout puts the tests of ``module`` (dotted), relative to tests/."""
    parts = module.split(".")
    if parts[0] != "signorini":
        return Path(f"test_{parts[-1]}.py")
    folder = parts[1:] if package else parts[1:-1]
    return Path(*folder, f"test_{parts[-1]}.py")


def imported_modules(path: Path) -> set[str]:
    """Every module a file imports, anywhere in it; ``from a import b`` counts as ``a`` and ``a.b``."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names |= {node.module} | {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def layout_problems(src: Path, tests: Path, exempt: dict[str, str]) -> list[str]:
    """What breaks the layout: a module without its test module, a test module that does not import
    its module, a test module (outside tests/end_to_end/) of no module, a stale exemption."""
    expected = {}
    for path in sorted(src.rglob("*.py")):
        if path.name != "__main__.py" and holds_code(path):
            module = _module_name(path, src)
            expected[module] = layout_test_module(module, path.name == "__init__.py")
    problems = [f"{module}: exempt but not a module of src/" for module in sorted(set(exempt) - set(expected))]
    for module, rel in expected.items():
        if module in exempt:
            continue
        if not (tests / rel).is_file():
            problems.append(f"{module}: no tests/{rel.as_posix()}")
        elif module not in imported_modules(tests / rel):
            problems.append(f"tests/{rel.as_posix()} does not import {module}")
    allowed = set(expected.values()) | {Path(name) for name in REPOSITORY_CHECKS}
    scripts = src.parent / BENCHMARKS
    allowed |= {Path(BENCHMARKS, f"test_{p.name}") for p in scripts.glob("*.py")} if scripts.is_dir() else set()
    for path in sorted(tests.rglob("test_*.py")):
        rel = path.relative_to(tests)
        if rel.parts[0] != END_TO_END and rel not in allowed:
            problems.append(f"tests/{rel.as_posix()} is the test module of no module of src/")
    return problems


def test_every_module_has_its_test_module_which_imports_it():
    assert layout_problems(SRC, ROOT / "tests", LAYOUT_EXEMPT) == []


FAKE_SRC = {
    "signorini/__init__.py": '"""The package."""\n',  # a docstring only: no tests of its own
    "signorini/cli.py": "def main(): ...\n",
    "signorini/fem/__init__.py": "",
    "signorini/fem/mesh.py": "def mesh(): ...\n",
    "signorini/solvers/__init__.py": "from signorini.solvers.qp import solve\n",  # code: tested itself
    "signorini/solvers/qp.py": "def solve(): ...\n",
    "plugin/__init__.py": "class Handler: ...\n",
}
FAKE_TESTS = {
    "test_architecture.py": "",
    "test_cli.py": "from signorini import cli\n",
    "test_plugin.py": "import plugin\n",
    "fem/test_mesh.py": "def test_mesh():\n    from signorini.fem.mesh import mesh\n",
    "solvers/test_solvers.py": "from signorini.solvers import solve\n",
    "solvers/test_qp.py": "import signorini.solvers.qp as qp\n",
    "end_to_end/test_workflow.py": "",  # a theme, no module
}


@pytest.mark.parametrize(
    ("change", "exempt", "problems"),
    [
        ({}, {}, []),
        ({"fem/test_mesh.py": None}, {}, ["signorini.fem.mesh: no tests/fem/test_mesh.py"]),
        ({"fem/test_mesh.py": "import numpy\n"}, {}, ["tests/fem/test_mesh.py does not import signorini.fem.mesh"]),
        ({"fem/test_mesh.py": "from signorini.fem import meshes\n"}, {},
         ["tests/fem/test_mesh.py does not import signorini.fem.mesh"]),
        ({"fem/test_mesh.py": None, "test_mesh.py": "from signorini.fem.mesh import mesh\n"}, {},
         ["signorini.fem.mesh: no tests/fem/test_mesh.py",
          "tests/test_mesh.py is the test module of no module of src/"]),
        ({"fem/test_faults.py": "from signorini.fem.mesh import mesh\n"}, {},
         ["tests/fem/test_faults.py is the test module of no module of src/"]),
        ({"solvers/test_solvers.py": None}, {}, ["signorini.solvers: no tests/solvers/test_solvers.py"]),
        ({"test_plugin.py": None}, {}, ["plugin: no tests/test_plugin.py"]),
        ({"fem/test_mesh.py": None}, {"signorini.fem.mesh": "a reason"}, []),
        ({}, {"signorini.fem.gone": "a reason"}, ["signorini.fem.gone: exempt but not a module of src/"]),
        ({"benchmarks/test_race.py": ""}, {}, []),
        ({"benchmarks/test_gone.py": ""}, {},
         ["tests/benchmarks/test_gone.py is the test module of no module of src/"]),
    ],
    ids=["complete", "missing", "not-imported", "similar-name", "misplaced", "theme-file", "package-init", "plugin",
         "exempt", "stale-exemption", "benchmark", "no-such-benchmark"],
)
def test_the_layout_check_finds_what_breaks_the_layout(tmp_path, change, exempt, problems):
    (tmp_path / "benchmarks").mkdir()
    (tmp_path / "benchmarks/race.py").write_text("def race(): ...\n", encoding="utf-8")
    for root, files in (("src", FAKE_SRC), ("tests", FAKE_TESTS | change)):
        for rel, text in files.items():
            if text is not None:
                (tmp_path / root / rel).parent.mkdir(parents=True, exist_ok=True)
                (tmp_path / root / rel).write_text(text, encoding="utf-8")
    assert layout_problems(tmp_path / "src", tmp_path / "tests", exempt) == problems


def test_the_thread_and_allocator_variables_are_named_in_one_module():
    """The environment a job computes in is set in one place (``signorini.pipeline.jobenv``):
    no other file of the tree names a thread or allocator variable."""
    from signorini.pipeline.jobenv import ALLOCATOR_VARIABLES, THREAD_VARIABLES

    files = [ROOT / "Snakefile", *(p for d in ("src", "workflow", "benchmarks", "tests", "notebooks")
                                   for p in (ROOT / d).rglob("*") if p.suffix in (".py", ".smk"))]
    naming = {
        str(p.relative_to(ROOT))
        for p in files
        if any(name in p.read_text(encoding="utf-8") for name in (*THREAD_VARIABLES, *ALLOCATOR_VARIABLES))
    }
    assert naming == {"src/signorini/pipeline/jobenv.py"}


def _third_party_imports(top_level_only: bool) -> dict[str, set[str]]:
    """{imported top-level module: the files of src/ that import it}, standard library and the
    project's own packages left out; ``top_level_only``: the imports a module runs when imported
    (not those inside functions, which run only when called)."""
    import sys

    own = {p.name for p in (ROOT / "src").iterdir() if p.is_dir()}
    found: dict[str, set[str]] = {}
    for path in (ROOT / "src").rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        nodes = tree.body if top_level_only else list(ast.walk(tree))
        for node in nodes:
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in (n.split(".")[0] for n in names):
                if name not in sys.stdlib_module_names and name not in own:
                    found.setdefault(name, set()).add(str(path.relative_to(ROOT)))
    return found


def _declared() -> tuple[set[str], set[str]]:
    """The project's dependencies and its extras' (normalised distribution names), from pyproject.toml."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]

    def names(specs):
        return {re.split(r"[<>=!~\[; ]", spec, maxsplit=1)[0].lower().replace("_", "-") for spec in specs}

    extras = [spec for extra in project["optional-dependencies"].values() for spec in extra]
    return names(project["dependencies"]), names(extras)


@functools.cache
def _packages_distributions() -> dict[str, list[str]]:
    """{top-level module: its distributions}: one scan of the installed distributions' records."""
    from importlib.metadata import packages_distributions

    return packages_distributions()


def _distribution(module: str) -> str:
    dists = _packages_distributions().get(module) or [module]  # not installed (an optional extra): its own name
    return dists[0].lower().replace("_", "-")


def test_what_the_package_imports_it_declares():
    """Every third-party module src/ imports is a dependency of pyproject.toml: one the package
    imports when imported is required, one imported inside a function (an optional route, the
    workflow, the notebooks) at least an extra."""
    required, extras = _declared()
    at_import = {_distribution(m): files for m, files in _third_party_imports(top_level_only=True).items()}
    anywhere = {_distribution(m): files for m, files in _third_party_imports(top_level_only=False).items()}
    plugin = {"snakemake-interface-logger-plugins"}  # the logger plugin's package, loaded by Snakemake only
    assert _undeclared(at_import, required | plugin) == {}, "imported on import but not in [project] dependencies"
    assert _undeclared(anywhere, required | extras) == {}, "imported but declared nowhere in pyproject.toml"
    # the check finds a dependency left out: meshio, which signorini.vtu imports on import
    assert "meshio" in _undeclared(at_import, (required | plugin) - {"meshio"})


def _undeclared(imported: dict[str, set[str]], declared: set[str]) -> dict[str, list[str]]:
    return {dist: sorted(files) for dist, files in imported.items() if dist not in declared}
