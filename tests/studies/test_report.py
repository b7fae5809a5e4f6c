"""The report's plan and pages (``signorini.studies.report``); the built report is tested in
``tests/end_to_end/test_report.py``."""

from __future__ import annotations

import shutil

from signorini.pipeline.paths import FIGURES
from signorini.studies import report


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
    (tmp_path / "results/paper/errors.csv").write_text("N,h,L4\n", encoding="utf-8")
    assert not report.plan(tmp_path, config)[0].built_here  # errors.csv alone: eoc.csv is missing
    (tmp_path / "results/paper/eoc.csv").write_text("N,h,L4\n", encoding="utf-8")
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
