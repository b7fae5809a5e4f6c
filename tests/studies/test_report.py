"""The report's plan and pages (``signorini.studies.report``); the built report is tested in
``tests/end_to_end/test_report.py``."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from helpers import ERRORS, copy_repo

from signorini.pipeline.paths import FIGURES, REPORT_PAGES, REPORT_SCENE_PAGE, report_page
from signorini.studies import report

# the eoc.csv of helpers.ERRORS
EOC = "N,h,L4\n21,0.0476,1.8\n41,0.0244,1.8\nregression,,1.8\n"


def test_a_study_is_built_here_only_with_its_cached_results(tmp_path):
    (tmp_path / "paper_figures").mkdir()
    config = {"figures_scene": "paper", "scenes": {"paper": {"N": [11, 21]}}}
    assert all(not s.rules for s in report.plan(tmp_path, config))  # nothing at all
    for path in (*FIGURES["table1"].values(), *FIGURES["table2"].values()):
        (tmp_path / path).write_text("x", encoding="utf-8")
    paper = report.plan(tmp_path, config)[0]
    assert paper.rules == ["table1", "table2"] and not paper.built_here  # committed files only
    assert "committed" in paper.status and "missing: figure2" in paper.status
    (tmp_path / "results/paper").mkdir(parents=True)
    (tmp_path / "results/paper/errors.csv").write_text(ERRORS, encoding="utf-8")
    assert not report.plan(tmp_path, config)[0].built_here  # errors.csv alone: eoc.csv is missing
    (tmp_path / "results/paper/eoc.csv").write_text(EOC, encoding="utf-8")
    assert report.plan(tmp_path, config)[0].built_here
    # the reproduction report needs Tables 1-2: without them it is not in the report
    shutil.rmtree(tmp_path / "paper_figures")
    (tmp_path / "paper_figures").mkdir()
    (tmp_path / FIGURES["reproduction"]["md"]).write_text("x", encoding="utf-8")
    assert "reproduction" in report.plan(tmp_path, config)[0].missing


def test_markdown_page_renders_tables_inline_and_escapes_html():
    text = "# T\n\n| h | L⁴(Ω) |\n| --- | ---: |\n| 1/11 | 5.8·10⁻⁴ |\n\n<script>x</script>\n"
    page = report.markdown_page(text, "t")
    assert "<table>" in page and '<td style="text-align:right">5.8·10⁻⁴</td>' in page
    assert "<script>x" not in page and "&lt;script&gt;" in page
    assert page.startswith("<!DOCTYPE html>") and 'charset="utf-8"' in page


def test_a_damaged_cached_table_is_named_skipped_and_not_called_built(tmp_path, monkeypatch, capsys):
    """A cut-off ``errors.csv`` (and an ``eoc.csv`` with a broken row): no scene page, the study is
    not built here, one line per file naming it and the command that rebuilds it; no traceback."""
    paper = tmp_path / "results/paper"
    paper.mkdir(parents=True)
    (paper / "errors.csv").write_text(ERRORS[:-9], encoding="utf-8")
    (paper / "eoc.csv").write_text(EOC.replace("1.8", "x", 1), encoding="utf-8")
    (tmp_path / "paper_figures").mkdir()
    for path in (*FIGURES["table1"].values(), *FIGURES["table2"].values()):
        (tmp_path / path).write_text("x", encoding="utf-8")
    (tmp_path / "workflow").mkdir()
    (tmp_path / "workflow/config.yaml").write_text(
        "figures_scene: paper\nscenes:\n  paper: {N: [11, 21, 41]}\n", encoding="utf-8"
    )
    config = {"figures_scene": "paper", "scenes": {"paper": {"N": [11, 21, 41]}}}
    study = report.plan(tmp_path, config)[0]
    assert not study.built_here and sorted(study.damaged) == ["results/paper/eoc.csv", "results/paper/errors.csv"]
    assert report.built_scenes(tmp_path, config) == []
    assert "is damaged (cut off (no final newline))" in report.scene_markdown("paper", paper / "errors.csv", None)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(report, "_snakemake", lambda *args: 0)
    assert report.build() == 0
    out = capsys.readouterr().out
    assert "skipped results/paper/errors.csv: damaged (cut off (no final newline)); `snakemake -c2 " \
           "results/paper/errors.csv` rebuilds it" in out.splitlines()
    assert out.count("skipped ") == 2 and "built on this machine" not in out


def test_committed_files_are_the_bytes_of_git_head(tmp_path):
    """Outputs without their cached results are called the repository's committed files only when
    git's HEAD holds the same bytes; an output computed (or edited) here is not; without git it is
    not known, and not claimed."""
    config = {"figures_scene": "paper", "scenes": {"paper": {"N": [11, 21]}}}
    (tmp_path / "paper_figures").mkdir()
    outputs = [*FIGURES["table1"].values(), *FIGURES["table2"].values()]
    for path in outputs:
        (tmp_path / path).write_text("committed", encoding="utf-8")
    assert report.plan(tmp_path, config)[0].committed is None  # no repository
    assert "is not known" in report.plan(tmp_path, config)[0].status

    def git(*args: str) -> None:
        subprocess.run(["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t", *args],
                       check=True, capture_output=True)

    git("init", "-q")
    git("add", *outputs)
    git("commit", "-q", "-m", "tables")
    paper = report.plan(tmp_path, config)[0]
    assert paper.committed and "the repository's committed files (the bytes of git's HEAD)" in paper.status
    (tmp_path / outputs[0]).write_text("computed here", encoding="utf-8")
    paper = report.plan(tmp_path, config)[0]
    assert paper.committed is False and "differ from the repository's committed ones" in paper.status
    assert "the repository's committed files" not in paper.status


# --- the report's menu and search --------------------------------------------------------------

# (path, category, subcategory, labels) of one entry of the report
Entry = tuple[str, str, str, dict[str, str]]


# parsed in a child process: importing snakemake.api loads PuLP, after which OSQP's set-up crashes
# the interpreter (a clash of their native libraries), and a test of the cvxpy routes may share
# this worker process
ENTRIES = """
import json, sys
from pathlib import Path
from snakemake.api import SnakemakeApi
from snakemake.settings.enums import Quietness
from snakemake.settings.types import OutputSettings, ResourceSettings

repo, page = Path(sys.argv[1]), sys.argv[2]
scenes = sys.argv[3:]
entries = []
with SnakemakeApi(OutputSettings(quiet={Quietness.ALL}, enable_file_logging=False)) as api:
    workflow = api.workflow(ResourceSettings(), snakefile=repo / "Snakefile", workdir=repo)._workflow
    for rule in workflow.rules:
        for out in rule.output:
            if (flag := out.flags.get("report")) is None:
                continue
            for scene in scenes if "{scene" in str(out) else ("",):
                path = page.format(scene=scene) if scene else str(out)
                labels = {k: str(v).replace("{scene}", scene) for k, v in (flag.labels or {}).items()}
                sub = (flag.subcategory or "Other").replace("{scene}", scene)
                entries.append((path, flag.category or "Other", sub, labels))
print(json.dumps(entries))
"""


def workflow_entries(repo: Path, scenes: tuple[str, ...] = ("paper", "smoke")) -> list[Entry]:
    """Every output the workflow marks for Snakemake's report, parsed from the Snakefile in
    ``repo`` (no DAG, no job): the scene page once per scene of ``scenes``."""
    import json
    import subprocess
    import sys

    args = [sys.executable, "-c", ENTRIES, str(repo), REPORT_SCENE_PAGE, *scenes]
    proc = subprocess.run(args, cwd=repo, capture_output=True, text=True, encoding="utf-8", timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return [tuple(entry) for entry in json.loads(proc.stdout.strip().splitlines()[-1])]


def menu_rows(listing: list[Entry]) -> tuple[dict[tuple[str, ...], list[str]], list[str]]:
    """The rows Snakemake's report (9.27, abstract_results.js ``getData``) draws for a list of its
    entries, a subcategory or a search: ({row's label values: the entries' paths}, the label
    columns drawn as a switch). The columns are the label names in order of first appearance; a
    column after the first with exactly two values, each on half the entries, becomes a switch
    over one row; an entry without a label has "" in its column."""
    first: dict[str, int] = {}
    for *_, labels in listing:
        for i, name in enumerate(labels):
            first.setdefault(name, i)
    columns = sorted(first, key=first.get)
    toggles = []
    for name in columns[1:]:
        values = [labels[name] for *_, labels in listing if name in labels]
        if len(set(values)) == 2 and all(2 * values.count(v) == len(listing) for v in set(values)):
            toggles.append(name)
    rows: dict[tuple[str, ...], list[str]] = {}
    for path, *_, labels in listing:
        rows.setdefault(tuple(labels.get(c, "") for c in columns if c not in toggles), []).append(path)
    return rows, toggles


def test_every_page_and_file_has_its_own_row_in_the_reports_menu_and_search(tmp_path, monkeypatch):
    """The report's menu and search make one row per distinct label tuple, so each entry needs
    its own: every Markdown output's page is listed (labelled as its file, view "page") beside the
    file's download, in the same subcategory; no label column turns into a switch."""
    monkeypatch.chdir(tmp_path)  # the workflow API changes the working directory
    entries = workflow_entries(copy_repo(tmp_path))
    names = sorted({name for *_, labels in entries for name in labels})
    tuples = [tuple(labels.get(n, "") for n in names) for *_, labels in entries]
    assert len(set(tuples)) == len(tuples), sorted(t for t in tuples if tuples.count(t) > 1)
    where = {path: (category, sub, labels) for path, category, sub, labels in entries}
    for page, source in REPORT_PAGES.items():
        assert where[report_page(page)] == (*where[source][:2], report.page_labels(Path(source).name)), page
        assert where[source][2] == {"file": Path(source).name}, source  # the file's download
    listings = {"everything": entries}  # a search matches paths; "" matches every entry
    for category, sub in {(c, s) for _, c, s, _ in entries}:
        listings[f"menu {category}/{sub}"] = [e for e in entries if e[1:3] == (category, sub)]
    for page in (*REPORT_PAGES, "scene_", ".html", ".md"):
        listings[f"search {page}"] = [e for e in entries if page in e[0]]
    for name, listing in listings.items():
        rows, toggles = menu_rows(listing)
        assert not toggles, (name, toggles)
        assert all(len(paths) == 1 for paths in rows.values()), (name, rows)
