"""The Snakemake report (``make report``, ``signorini.studies.report``): every table and figure
that exists is in it with its caption, the Markdown outputs as inline HTML pages; it says per
study whether it was built here or comes from the committed files, and works on a fresh clone."""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import ROOT, clone_built, copy_repo

from signorini.pipeline.paths import FIGURES, REPORT_CONTENTS, REPORT_PAGES, TARGETS, report_page
from signorini.studies import report

CATEGORIES = {
    "all": "Paper",
    "theory": "Theory",
    "work_precision": "Work precision",
    "stability": "Stability",
    "true_norms": "Paper",
    "fine": "Theory",
    "finest": "Theory",
    "meshes": "Theory",
}
RULE_CATEGORIES = {"summary": "Findings"}  # a rule whose outputs the report files apart from its target's


def embedded(html: str, name: str) -> dict:
    """An object the HTML report embeds: ``results`` ({path: {caption, data_uri, ...}}) or
    ``categories`` ({category: {subcategory: [path, ...]}})."""
    m = re.search(rf"var {name} = (\{{.*?\}});\n", html, flags=re.S)
    assert m, f"no {name} in the report"
    return json.loads(m.group(1))


def make_report(repo: Path) -> subprocess.CompletedProcess:
    """What ``make report`` runs, in ``repo``."""
    return subprocess.run(
        [sys.executable, "-m", "signorini.studies.report", "build"],
        cwd=repo, capture_output=True, text=True, timeout=900,
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": str(repo / "src")},
    )


def page_text(results: dict, path: str) -> str:
    return base64.b64decode(results[path]["data_uri"].split("base64,", 1)[1]).decode("utf-8")


@pytest.mark.slow
def test_report_holds_every_table_and_figure(built_repo, tmp_path):
    repo = clone_built(built_repo, tmp_path / "repo")
    assert [s.target for s in report.plan(repo) if s.built_here and not s.missing] == list(TARGETS)
    proc = make_report(repo)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    out = proc.stdout + proc.stderr
    assert "Missing metadata" not in out and "Traceback" not in out
    assert len(out.splitlines()) < 20, out  # the status per study, no flood
    assert out.count("built on this machine") == len(TARGETS)
    html = (repo / "results/report.html").read_text(encoding="utf-8")
    results, categories = embedded(html, "results"), embedded(html, "categories")
    for target, rules in TARGETS.items():
        for rule in rules:
            category = RULE_CATEGORIES.get(rule, CATEGORIES[target])
            listed = {path for paths in categories[category].values() for path in paths}
            for path in FIGURES[rule].values():
                assert path in results and path in listed, f"{path} is not in the report under {category}"
                caption = results[path]["caption"]
                assert caption.strip() and "ERROR" not in caption and "System Message" not in caption, path
                assert results[path]["data_uri"].startswith("data:"), path  # self-contained
    for page, source in REPORT_PAGES.items():  # every Markdown output also as an inline HTML page
        path = report_page(page)
        assert results[path]["mime_type"] == "text/html", path  # shown inline, not as a download
        assert results[path]["caption"] == results[source]["caption"], path
        text = page_text(results, path)
        assert "<table>" in text or page in ("summary", "theory", "work_precision", "stability"), path
        assert "<h1>" in text or "<strong>" in text, path
    table1 = page_text(results, report_page("table1"))
    assert "<th" in table1 and "1/21" in table1 and "·10" in table1  # the smoke scene's rows, as in table1.md
    for scene in ("smoke", "mine"):  # each scene's errors and EOCs, under its scene
        page = f"results/report/scene_{scene}.html"
        assert page in categories["Scenes"][scene]
        assert "regr." in page_text(results, page)
    assert "built on this machine" in page_text(results, REPORT_CONTENTS)
    assert "Replication of the numerical experiments" in html  # the workflow description


@pytest.mark.slow
def test_report_of_a_fresh_clone_shows_the_committed_outputs(tmp_path):
    """A clone with the committed paper_figures/ and nothing built: no crash, every committed
    output in the report, each study named as the repository's committed files."""
    repo = copy_repo(tmp_path)
    measured = Path(FIGURES["runtime"]["csv"]).name  # git-ignored: a run of this checkout may have left it
    shutil.copytree(ROOT / "paper_figures", repo / "paper_figures", ignore=shutil.ignore_patterns(measured))
    proc = make_report(repo)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    out = proc.stdout + proc.stderr
    assert "Traceback" not in out and "Missing metadata" not in out and len(out.splitlines()) < 20, out
    assert "built on this machine" not in out and out.count("committed files") == len(TARGETS)
    assert "missing: runtime" in out  # runtime.csv is a measurement of this machine: never committed
    results = embedded((repo / "results/report.html").read_text(encoding="utf-8"), "results")
    committed = {f"paper_figures/{p.name}" for p in (repo / "paper_figures").iterdir()}
    assert committed <= set(results), sorted(committed - set(results))
    for page in ("table1", "table2", "reproduction", "theory"):
        assert results[report_page(page)]["mime_type"] == "text/html"
    assert not (repo / "results/theory").exists()  # nothing was recomputed
