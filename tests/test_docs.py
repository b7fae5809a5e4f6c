"""The README and the pages in docs/ name only things that exist: every file, module, function and
test they mention in backticks, and every page they link to.

A name in backticks is checked when it has the shape of a reference: a repository path (with a
``/`` or a known suffix; ``{a,b}`` alternatives expanded), a dotted name under ``signorini``
(``signorini.fem.mesh.mesh_width``, or the short ``fem.…``, ``studies.…`` forms), or a test
(``tests/test_x.py::test_name``, or ``test_name`` alone: in some test module).  Templates
(``<scene>``), globs and what the pipeline writes under git-ignored directories (``results/``,
``.venv/``) are not files of the repository and are skipped.

docs/glossary.md defines the internal names (``GLOSSARY_TERMS``) that the pages and the outputs in
paper_figures/ mention.
"""

from __future__ import annotations

import importlib
import itertools
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
# evidence pages whose names are checked too (the README links them; the glossary check leaves them out)
EVIDENCE_PAGES = [ROOT / "docs" / "evidence" / "design-measurements.md"]
SUFFIXES = (".py", ".md", ".csv", ".json", ".yaml", ".yml", ".png", ".pdf", ".tex", ".rst", ".smk", ".txt", ".cff",
            ".lock", ".in", ".toml")
# written by the pipeline or the set-up, not part of the repository
GENERATED = ("results/", ".venv/", ".snakemake/", ".tools/", "paper_figures/runtime.csv", "u201.vtu")
PACKAGE_ROOTS = ("fem.", "solvers.", "pipeline.", "studies.", "paper.", "plotting.", "formatting.", "explore.")
# the package's own directories, against which a short path such as `fem/norms/conventional.py` is resolved
SEARCH_DIRS = (ROOT, ROOT / "src" / "signorini", ROOT / "workflow", ROOT / "workflow" / "scripts")


def _spans(text: str) -> list[str]:
    """Backtick spans outside fenced code blocks."""
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    return re.findall(r"`([^`\n]+)`", prose)


def _expand(span: str) -> list[str]:
    """`a/{b,c}.md` -> [a/b.md, a/c.md]"""
    parts = re.split(r"\{([^{}]*)\}", span)
    choices = [p.split(",") if i % 2 else [p] for i, p in enumerate(parts)]
    return ["".join(c) for c in itertools.product(*choices)]


def _is_path(span: str) -> bool:
    """A repository path: its first component is a directory of the repository or the package
    (`proctrack/linuxproc` and `H^1/2` are not), or a bare Python file name (`table.py`)."""
    if any(ch in span for ch in " <>*=()[]|$…^") or span.startswith(("-", "/", "http")):
        return False
    if "/" not in span:
        return span.endswith(".py") and len(span) > 3
    first = span.split("/")[0]
    return any((base / first).is_dir() for base in SEARCH_DIRS[:2]) or first in ("docs", "paper_figures")


def _path_exists(span: str) -> bool:
    path = span.split("::")[0].rstrip("/")
    if "/" not in path:  # a bare file name: somewhere in the tree
        return any(ROOT.glob(f"[!.]*/**/{path}")) or (ROOT / path).exists()
    return any((base / path).exists() for base in SEARCH_DIRS)


def _python_name(span: str) -> str | None:
    if not re.fullmatch(r"[A-Za-z_][\w.]*[\w]", span) or "." not in span:
        return None
    if span.startswith("signorini."):
        return span
    if span.startswith(PACKAGE_ROOTS) and not span.endswith(SUFFIXES):
        return "signorini." + span
    return None


def _resolves(name: str) -> bool:
    """The longest importable module prefix of ``name``, then attributes."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for attr in parts[k:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def _references(page: Path) -> list[tuple[str, str]]:
    """(kind, reference) of every checked name on a page."""
    refs = []
    text = page.read_text(encoding="utf-8")
    for span in _spans(text):
        if "::" in span and span.startswith("tests/"):
            refs.append(("test", span))
        elif re.fullmatch(r"test_\w+", span):  # a test named without its file
            refs.append(("test", f"tests/**/*.py::{span}"))
        elif (name := _python_name(span)) is not None:
            refs.append(("python", name))
        elif _is_path(span) and not span.startswith(GENERATED):
            refs.extend(("path", p) for p in _expand(span))
    for link in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
        if not link.startswith("http"):
            target = (page.parent / link).resolve()
            refs.append(("link", str(target.relative_to(ROOT) if target.is_relative_to(ROOT) else target)))
    return refs


def _exists(kind: str, ref: str) -> bool:
    if kind == "python":
        return _resolves(ref)
    if kind == "test":
        file, _, test = ref.partition("::")
        source = "\n".join(f.read_text(encoding="utf-8") for f in ROOT.glob(file))
        name = test.split("::")[-1].split("[")[0]
        return re.search(rf"^(def|class) {re.escape(name)}\b|^{re.escape(name)} = ", source, re.M) is not None
    return _path_exists(ref)


@pytest.mark.parametrize("page", PAGES + EVIDENCE_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_name_a_page_mentions_exists(page):
    missing = [f"{kind} {ref}" for kind, ref in _references(page) if not _exists(kind, ref)]
    assert not missing, f"{page.relative_to(ROOT)} names what does not exist: {missing}"


def test_the_checker_finds_missing_names(tmp_path):
    """The check itself can fail: made-up names of each kind are reported."""
    page = tmp_path / "page.md"
    page.write_text(
        "`src/signorini/no_such_module.py`, `signorini.fem.mesh.no_such_function`, "
        "`tests/test_docs.py::test_no_such_test`, `test_no_such_test_anywhere`, [a page](no-such-page.md)",
        encoding="utf-8",
    )
    refs = _references(page)
    assert len(refs) == 5 and not any(_exists(kind, ref) for kind, ref in refs)


def test_every_docs_page_is_linked_from_the_readme():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    unlinked = [p.name for p in PAGES[1:] if f"docs/{p.name}" not in readme]
    assert not unlinked, f"docs pages the README's map does not list: {unlinked}"


def test_the_readme_is_short():
    assert len((ROOT / "README.md").read_text(encoding="utf-8").splitlines()) <= 150


# Internal names of the outputs (paper_figures/*.md) and the pages (docs/*.md): each that a page
# mentions in backticks must be a term of docs/glossary.md (a bold term or a heading there).
GLOSSARY = ROOT / "docs" / "glossary.md"
GLOSSARY_TERMS = (
    # the problem and the mesh
    "sw_ne", "nw_se", "A_FF",
    # norms: the grammar, the suffixes, the conventions and their quadrature rules
    "Lp", "L2", "L4", "L16", "L32", "Linf", "W1p", "W12", "W14", "W116", "W132", "W1inf", "H1", "H12", "L2boundary",
    "L4plus", "L4minus", "plus", "minus", "_true", "_raw", "Conventions", "stroud4_acute1", "stroud4_acute2",
    "stroud4_right", "dunavant8", "components", "h12_boundary",
    # solvers
    "direct", "active_set", "multigrid", "auto", "kkt_tol", "vinewtonrsls", "vinewtonssls", "ok", "inaccurate",
    "failed", "skipped",
    # studies
    "algebraic_error", "theory_rates", "theory_extra", "cost_of_accuracy", "time_s", "wall_s", "time_ref", "ref_s",
    "load1", "spread", "cond_max_dofs", "meshes", "meshes_study", "meshes_rates", "slope_h", "order_n", "last_eoc",
    "vs_expected", "vs_reference", "quasi_uniform", "mesh", "friedrichs_keller", "union_jack", "graded", "delaunay",
    # the workflow
    "scene_defaults", "figures_scene", "norm_jobs", "per_norm", "per_mesh", "solver_options", "paper", "smoke",
    "case2", "fine", "finest", "theory", "work_precision", "stability",
)


def _backticked_names(page: Path) -> set[str]:
    """The identifiers inside a page's backtick spans, templates left out: `*_raw` holds `_raw`,
    `<norm>_true` holds `_true`, `signorini.fem.norms.conventions.Conventions` holds `Conventions`."""
    return {
        name
        for span in _spans(page.read_text(encoding="utf-8"))
        for name in re.findall(r"[A-Za-z_]\w*", re.sub(r"<[^<>]*>", "", span))
    }


def _glossary_entries(text: str) -> set[str]:
    """The terms a glossary defines: its bold terms and headings, without their backticks."""
    terms = re.findall(r"\*\*(.+?)\*\*", text) + re.findall(r"^#+\s+(.+?)\s*$", text, re.M)
    return {term.strip().strip("`") for term in terms}


def _undefined_terms(pages, glossary_text: str, terms=GLOSSARY_TERMS) -> dict[str, list[str]]:
    """{term: the pages that mention it} for each listed term the pages mention but the glossary
    does not define."""
    entries = _glossary_entries(glossary_text)
    mentions = {page: _backticked_names(page) for page in pages}
    return {
        term: [page.name for page, names in mentions.items() if term in names]
        for term in terms
        if term not in entries and any(term in names for names in mentions.values())
    }


def test_the_glossary_defines_every_internal_name_the_outputs_and_pages_use():
    pages = [p for p in PAGES[1:] if p != GLOSSARY] + sorted((ROOT / "paper_figures").glob("*.md"))
    assert any(set(GLOSSARY_TERMS) & _backticked_names(p) for p in pages), "no listed term found: the check is blind"
    missing = _undefined_terms(pages, GLOSSARY.read_text(encoding="utf-8"))
    assert not missing, f"terms without an entry (bold term or heading) in docs/glossary.md: {missing}"


def test_the_glossary_check_finds_an_undefined_term(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("The `sw_ne` mesh, columns `*_raw`, the `<norm>_true` norms and `per_mesh` jobs.", encoding="utf-8")
    glossary = "# Glossary\n\n- **`sw_ne`**: the / diagonal.\n- **`_true`**, **`_raw`**: suffixes.\n"
    assert _undefined_terms([page], glossary) == {"per_mesh": ["page.md"]}


@pytest.mark.parametrize("caption", sorted((ROOT / "workflow" / "report").glob("*.rst")), ids=lambda p: p.name)
def test_every_report_caption_is_valid_restructuredtext(caption):
    """Snakemake renders the captions with docutils: a stray ``|x|`` is a substitution it cannot
    resolve, and the report prints an error in place of the caption."""
    import io

    from docutils.core import publish_string

    errors = io.StringIO()
    publish_string(
        caption.read_text(encoding="utf-8"),
        writer_name="html",
        settings_overrides={"warning_stream": errors, "report_level": 3, "halt_level": 5},
    )
    assert not errors.getvalue(), errors.getvalue()
