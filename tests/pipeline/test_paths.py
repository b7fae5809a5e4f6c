"""Every path of the workflow (``signorini.pipeline.paths``): templates filled as far as their
wildcards are given, no file written by two rules, the report's pages drawn from existing outputs."""

from __future__ import annotations

import re

from signorini.pipeline.paths import (
    BENCHMARKS,
    FIGDIR,
    FIGURES,
    LOGS,
    PATHS,
    RENDER_INPUTS,
    REPORT_PAGES,
    RESULTS,
    TARGETS,
    benchmark,
    log,
    report_page,
)


def test_log_and_benchmark_templates_fill_the_given_wildcards_only():
    assert log("mesh", "solve") == "results/{scene}/logs/N{N}/solve.log"
    assert log("mesh", "norm_{norm}", scene="smoke") == "results/smoke/logs/N{N}/norm_{norm}.log"
    assert log("case", "stability_case", scene="s", case="A_1") == "results/s/logs/atlas/A_1.log"
    assert benchmark("mesh", "solve", N="21") == "results/{scene}/benchmarks/N21/solve.tsv"
    assert report_page("table1") == "results/report/table1.html"


def test_no_two_rules_write_one_file_and_every_artifact_lies_under_results():
    outputs = [path for rule in FIGURES.values() for path in rule.values()]
    assert len(outputs) == len(set(outputs)) and all(p.startswith(f"{FIGDIR}/") for p in outputs)
    artifacts = [*PATHS.values(), *LOGS.values(), *BENCHMARKS.values()]
    assert len(artifacts) == len(set(artifacts)) and all(p.startswith(f"{RESULTS}/") for p in artifacts)
    for template in PATHS.values():  # every artifact of a mesh or a case is named by its wildcards
        assert set(re.findall(r"{(\w+)}", template)) <= {"scene", "N", "norm", "case", "solver"}


def test_targets_render_inputs_and_report_pages_name_existing_outputs():
    rendered = {rule for rules in TARGETS.values() for rule in rules}
    assert rendered == set(FIGURES)  # every rendering rule belongs to one target
    assert len(rendered) == sum(len(rules) for rules in TARGETS.values())
    assert all(rule in FIGURES and set(inputs) <= set(FIGURES) for rule, inputs in RENDER_INPUTS.items())
    outputs = {path for rule in FIGURES.values() for path in rule.values()}
    assert set(REPORT_PAGES.values()) <= outputs and all(p.endswith(".md") for p in REPORT_PAGES.values())


def test_the_report_pages_and_targets_are_stated_once_with_their_captions_and_commands():
    """``REPORT_PAGES`` and ``TARGETS`` are views of ``REPORT_PAGE_ENTRIES`` and ``TARGET_RULES``;
    every page's caption is a file of workflow/report/."""
    from helpers import ROOT

    from signorini.pipeline.paths import REPORT_PAGE_ENTRIES, TARGET_RULES

    assert REPORT_PAGES == {page: entry.source for page, entry in REPORT_PAGE_ENTRIES.items()}
    assert TARGETS == {name: target.rules for name, target in TARGET_RULES.items()}
    assert all((ROOT / "workflow/report" / f"{entry.caption}.rst").is_file() for entry in REPORT_PAGE_ENTRIES.values())
    assert TARGET_RULES["all"].command == "make all"
    assert all(t.command == f"snakemake -c2 {name}" for name, t in TARGET_RULES.items() if name != "all")
