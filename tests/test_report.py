"""The Snakemake report (``make report``): every table and figure of the built test workflow is in
it, with its caption and its study's category."""

from __future__ import annotations

import json
import re

import pytest
from helpers import snakemake

from signorini.pipeline.paths import FIGURES, PATHS, TARGETS, built_targets

CATEGORIES = {
    "all": "Paper",
    "theory": "Theory",
    "work_precision": "Work precision",
    "stability": "Stability",
    "true_norms": "Paper",
}


def embedded(html: str, name: str) -> dict:
    """An object the HTML report embeds: ``results`` ({path: {caption, data_uri, ...}}) or
    ``categories`` ({category: {subcategory: [path, ...]}})."""
    m = re.search(rf"var {name} = (\{{.*?\}});\n", html, flags=re.S)
    assert m, f"no {name} in the report"
    return json.loads(m.group(1))


@pytest.mark.slow
def test_report_holds_every_table_and_figure(built_repo, tmp_path):
    targets = built_targets(built_repo)
    assert targets == list(TARGETS)  # every study of the test workflow is built
    out = tmp_path / "report.html"
    snakemake(built_repo, "--report", str(out), *targets)
    html = out.read_text()
    results, categories = embedded(html, "results"), embedded(html, "categories")
    for target, rules in TARGETS.items():
        listed = {path for paths in categories[CATEGORIES[target]].values() for path in paths}
        for rule in rules:
            for path in FIGURES[rule].values():
                assert path in results and path in listed, f"{path} is not in the report under {CATEGORIES[target]}"
                caption = results[path]["caption"]
                assert caption.strip() and "ERROR" not in caption and "System Message" not in caption, path
                assert results[path]["data_uri"].startswith("data:"), path  # self-contained
    for table in ("errors_csv", "eoc_csv"):  # the scenes' tables, under their scene
        assert PATHS[table].format(scene="smoke") in results
    assert "Replication of the numerical experiments" in out.read_text()  # the workflow description


def test_nothing_built_means_no_report_target(tmp_path):
    (tmp_path / "workflow").mkdir()
    (tmp_path / "workflow/config.yaml").write_text("figures_scene: paper\n")
    assert built_targets(tmp_path) == []
