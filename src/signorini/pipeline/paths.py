"""Every path of the workflow, defined once: cached artifacts, logs, benchmark files, the
published reference tables and the rendered outputs in ``paper_figures/``.

Templates use Snakemake's wildcards (``{scene}``, ``{N}``, ``{norm}``, ``{case}``, ``{solver}``);
the rules, the cache checks, the notebooks' helpers and the tests all read them from here.
"""

from __future__ import annotations

from typing import NamedTuple

RESULTS = "results"  # the cached artifacts, logs and benchmark files
FIGDIR = "paper_figures"
# the seals of the files a job writes that carry no checksum of their own (tables, pages, figures):
# results/.seals/<path>.json, signorini.pipeline.artifacts.seal_path
SEALS = f"{RESULTS}/.seals"
THEORY_SCENE = "theory"  # the scene rendered into paper_figures/theory* (its jobs: theory_quantities)
REFERENCE = "workflow/reference"
_MESH = "results/{scene}/N{N}"

PATHS = {
    # the chain of every scene: (mesh ->) discretise -> solve -> norm -> errors/eoc; the mesh
    # stage runs for a scene that names a mesh family (studies.scene.mesh)
    "mesh_npz": f"{_MESH}/mesh.npz",
    "mesh_json": f"{_MESH}/mesh.json",
    "mesh_vtu": f"{_MESH}/mesh.vtu",
    "system_npz": f"{_MESH}/system.npz",
    "system_json": f"{_MESH}/system.json",
    "solution_npz": f"{_MESH}/solution.npz",
    "solution_json": f"{_MESH}/solution.json",
    "solution_vtu": f"{_MESH}/solution.vtu",
    "norm_json": f"{_MESH}/norms/{{norm}}.json",
    "errors_csv": "results/{scene}/errors.csv",
    "eoc_csv": "results/{scene}/eoc.csv",
    "fields_npz": "results/{scene}/fields.npz",
    "h12_boundary_csv": "results/{scene}/h12_boundary.csv",
    # Table 1's norms with the load vector integrated by the norms' 16-point rule instead
    "load_rule_csv": "results/{scene}/load_rule.csv",
    # the studies beyond the paper
    "theory_json": f"{_MESH}/theory.json",
    "atlas_case_json": "results/{scene}/atlas/{case}.json",
    "atlas_case_npz": "results/{scene}/atlas/{case}.npz",
    "wp_measure_json": f"{_MESH}/work_precision/{{solver}}.json",
}

# one log and (for the computing rules) one benchmark file per job; {name} is the rule's
# file stem, e.g. "solve" or "norm_{norm}"
LOGS = {
    "mesh": "results/{scene}/logs/N{N}/{name}.log",
    "scene": "results/{scene}/logs/{name}.log",
    "case": "results/{scene}/logs/atlas/{case}.log",
}
BENCHMARKS = {
    "mesh": "results/{scene}/benchmarks/N{N}/{name}.tsv",
    "case": "results/{scene}/benchmarks/atlas/{case}.tsv",
}

# the PETSc peers' driver: an external program (stdlib, numpy, petsc4py), a code input of its jobs
PEER_DRIVER = "workflow/peers/petsc_peer.py"
IMPORT_CACHE = ".snakemake/signorini/imports.json"  # codedeps.ImportCache: each file's direct imports
# config.validate_config: the last validated config, keyed by the digest of the config, schema and checks
VALIDATED_CONFIG = ".snakemake/signorini/validated-config.json"

REFERENCES = {
    "paper_table1": f"{REFERENCE}/paper_table1.csv",
    "paper_table2": f"{REFERENCE}/paper_table2.csv",
    "remarks": f"{REFERENCE}/deviation_remarks.md",
    # every combination of the conventions against the published Table 1 (benchmarks/conventions.py)
    "conventions": "docs/evidence/conventions.csv",
}


def _outputs(name: str, *exts: str) -> dict[str, str]:
    return {ext: f"{FIGDIR}/{name}.{ext}" for ext in exts}


# the rendered outputs, by rule: {name: path}
FIGURES = {
    "table1": _outputs("table1", "csv", "md", "tex"),
    "table2": _outputs("table2", "csv", "md", "tex"),
    "figure2": _outputs("figure2", "pdf", "png"),
    "figure3": _outputs("figure3", "pdf", "png"),
    "reproduction": _outputs("reproduction", "md"),
    "runtime": _outputs("runtime", "csv"),
    "theory_report": {
        **_outputs("theory", "md", "csv"),
        "rates_csv": f"{FIGDIR}/theory_rates.csv",  # the data of theory_rates.png
        **{f"rates_{k}": v for k, v in _outputs("theory_rates", "pdf", "png").items()},
        **{f"extra_{k}": v for k, v in _outputs("theory_extra", "pdf", "png").items()},
    },
    "work_precision_table": _outputs("work_precision", "csv"),
    "work_precision_figures": {
        **_outputs("work_precision", "pdf", "png"),
        **{f"cost_{k}": v for k, v in _outputs("cost_of_accuracy", "pdf", "png").items()},
    },
    "work_precision_report": _outputs("work_precision", "md"),
    "stability_atlas": _outputs("stability", "csv", "md", "pdf", "png"),
    "true_tables": {
        **{f"table1_{k}": v for k, v in _outputs("table1_true", "csv", "md").items()},
        **{f"table2_{k}": v for k, v in _outputs("table2_true", "csv", "md").items()},
    },
    **{
        f"{scene}_tables": {
            **{f"table1_{k}": v for k, v in _outputs(f"table1_{scene}", "csv", "md").items()},
            **{f"table2_{k}": v for k, v in _outputs(f"table2_{scene}", "csv", "md").items()},
        }
        for scene in ("fine", "finest")
    },
    # the discrete contact sets of the theory scene against the exact one, condition (A_h)
    "contact_set": _outputs("contact_set", "csv", "pdf", "png"),
    # the EOCs of the seven norms against h, h = 1/101 ... 1/4001, true norms and conventions
    "eoc_against_h": _outputs("eoc_against_h", "pdf", "png"),
    # |u - u_h| near the free point (x0, 0) and the conventions' point sets
    "free_point_error": _outputs("free_point_error", "pdf", "png"),
    # the findings of every study in one page
    "summary": _outputs("summary", "md"),
    # Theorem 6.1's rates on the mesh families (studies.meshes): findings, rates, figure
    "meshes_report": {
        **_outputs("meshes", "md", "csv"),
        **{f"rates_{k}": v for k, v in _outputs("meshes_rates", "pdf", "png").items()},
    },
}


def log(kind: str, name: str, **wildcards: str) -> str:
    """A log path template (``kind``: ``mesh``, ``scene`` or ``case``), wildcards left open
    unless given: ``log("mesh", "solve")`` -> ``results/{scene}/logs/N{N}/solve.log``."""
    return LOGS[kind].replace("{name}", name).format_map(_Open(wildcards))


def benchmark(kind: str, name: str, **wildcards: str) -> str:
    """A benchmark path template, like ``log``."""
    return BENCHMARKS[kind].replace("{name}", name).format_map(_Open(wildcards))


class _Open(dict):
    """Format mapping that leaves unknown wildcards as they are."""

    def __missing__(self, key: str) -> str:
        return "{" + key + "}"


class Target(NamedTuple):
    """A target rule: the rules whose outputs it renders, what the report calls it and the command
    that computes it."""

    rules: tuple[str, ...]
    title: str
    command: str


# the target rules (the Snakefile's, the report's)
TARGET_RULES = {
    "all": Target(
        ("table1", "table2", "figure2", "figure3", "reproduction", "runtime", "summary"),
        "paper (Tables 1-2, Figures 2-3)",
        "make all",
    ),
    "theory": Target(("theory_report", "contact_set"), "theory scene", "snakemake -c2 theory"),
    "work_precision": Target(
        ("work_precision_table", "work_precision_figures", "work_precision_report"),
        "work-precision study",
        "snakemake -c2 work_precision",
    ),
    "stability": Target(("stability_atlas",), "stability atlas", "snakemake -c2 stability"),
    "true_norms": Target(("true_tables", "free_point_error"), "true norms", "snakemake -c2 true_norms"),
    "fine": Target(("fine_tables", "eoc_against_h"), "Table 2 to h = 1/4001", "snakemake -c2 fine"),
    "finest": Target(("finest_tables",), "Table 2 to h = 1/8001", "snakemake -c2 finest"),
    "meshes": Target(("meshes_report",), "mesh families", "snakemake -c2 meshes"),
}
TARGETS = {name: target.rules for name, target in TARGET_RULES.items()}  # the rules each target renders


# what a rendering rule reads from other rendering rules: it is in the report only with them
RENDER_INPUTS = {
    "reproduction": ("table1", "table2"),
    "summary": ("table1", "table2", "reproduction"),
    "work_precision_figures": ("work_precision_table",),
    "work_precision_report": ("work_precision_table",),
    "theory_report": ("contact_set",),
    "eoc_against_h": ("true_tables", "fine_tables"),
}

class ReportPage(NamedTuple):
    """A page of the report: the Markdown output it shows inline, and its place in the report's
    menu: the caption (``workflow/report/<caption>.rst``, as the rule that writes the source),
    category and subcategory."""

    source: str
    caption: str
    category: str
    subcategory: str | None = None


# The report's pages (signorini.studies.report, workflow/rules/report.smk), each rendered to
# results/report/<page>.html; and one page per scene with its errors and EOCs.
REPORT_DIR = "results/report"
REPORT_PAGE_ENTRIES = {
    "summary": ReportPage(FIGURES["summary"]["md"], "summary", "Findings"),
    "table1": ReportPage(FIGURES["table1"]["md"], "table1", "Paper", "Tables"),
    "table2": ReportPage(FIGURES["table2"]["md"], "table2", "Paper", "Tables"),
    "reproduction": ReportPage(FIGURES["reproduction"]["md"], "reproduction", "Paper", "Reproduction"),
    "table1_true": ReportPage(FIGURES["true_tables"]["table1_md"], "true_tables", "Paper", "True norms"),
    "table2_true": ReportPage(FIGURES["true_tables"]["table2_md"], "true_tables", "Paper", "True norms"),
    "table1_fine": ReportPage(FIGURES["fine_tables"]["table1_md"], "fine_tables", "Theory", "Finer meshes"),
    "table2_fine": ReportPage(FIGURES["fine_tables"]["table2_md"], "fine_tables", "Theory", "Finer meshes"),
    "table1_finest": ReportPage(FIGURES["finest_tables"]["table1_md"], "finest_tables", "Theory", "Finer meshes"),
    "table2_finest": ReportPage(FIGURES["finest_tables"]["table2_md"], "finest_tables", "Theory", "Finer meshes"),
    "theory": ReportPage(FIGURES["theory_report"]["md"], "theory", "Theory"),
    "work_precision": ReportPage(FIGURES["work_precision_report"]["md"], "work_precision", "Work precision"),
    "stability": ReportPage(FIGURES["stability_atlas"]["md"], "stability", "Stability"),
    "meshes": ReportPage(FIGURES["meshes_report"]["md"], "meshes", "Theory", "Mesh families"),
}
REPORT_PAGES = {page: entry.source for page, entry in REPORT_PAGE_ENTRIES.items()}  # {page: its Markdown source}
REPORT_SCENE_PAGE = f"{REPORT_DIR}/scene_{{scene}}.html"
REPORT_CONTENTS = f"{REPORT_DIR}/contents.html"  # what is in the report, built here or committed


def report_page(page: str) -> str:
    """The HTML page of ``page`` (a key of ``REPORT_PAGES``)."""
    return f"{REPORT_DIR}/{page}.html"
