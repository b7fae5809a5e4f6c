"""The Snakemake report's contents (``make report``): which results exist, which of them this
machine computed, and the HTML pages that show the Markdown outputs inline.

Snakemake's report shows an HTML file inline (in a frame) and any other text file only as a
download link, so every Markdown output (Tables 1-2, the reproduction report, the studies'
findings) gets a page: the same Markdown, rendered to HTML (``markdown_page``), by the rules of
``workflow/rules/report.smk``.  A page is rendered from the file as it is, whoever wrote it: a
committed output whose measurements are not in ``results/`` (a study takes long to compute:
docs/evidence/design-measurements.md#committed-study-outputs) is shown without being recomputed.
``plan`` says per study whether its outputs were computed from this machine's cached results
("built here", which needs those results intact), hold the bytes of the repository's committed
files (git's ``HEAD``), differ from them, or are missing, and lists the report's targets; a
damaged cached table is left out of the report, with one line naming it.
"""

from __future__ import annotations

import argparse
import hashlib
import html
import logging
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from signorini.pipeline import paths

CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; font-size: 14px;
       line-height: 1.45; color: #222; margin: 1.2em 1.6em; max-width: 72em; }
h1 { font-size: 1.5em; } h2 { font-size: 1.25em; margin-top: 1.4em; } h3 { font-size: 1.08em; }
table { border-collapse: collapse; margin: 0.8em 0; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #c8c8c8; padding: 0.25em 0.6em; }
th { background: #f0f0f0; } tr:nth-child(even) td { background: #fafafa; }
td:first-child, th:first-child { white-space: nowrap; }
code { background: #f3f3f3; padding: 0 0.2em; border-radius: 3px; font-size: 0.95em; }
"""


def markdown_page(text: str, title: str) -> str:
    """A self-contained HTML page of Markdown ``text`` (CommonMark with tables, as GitHub shows
    the file; raw HTML in the text is escaped, not passed through)."""
    from markdown_it import MarkdownIt

    body = MarkdownIt("commonmark", {"html": False}).enable("table").render(text)
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f"<title>{html.escape(title)}</title>\n<style>{CSS}</style>\n</head>\n<body>\n{body}</body>\n</html>\n"
    )


def scene_markdown(scene: str, errors_csv: str | os.PathLike, eoc_csv: str | os.PathLike | None) -> str:
    """A scene's ``errors.csv`` and ``eoc.csv`` as Markdown tables (five significant digits; the
    CSV files hold every digit)."""
    import pandas as pd

    from signorini.formatting import h_label, md_table, sci_md
    from signorini.pipeline.integrity import table_defect
    from signorini.published import label_md

    if (defect := table_defect(errors_csv)) is not None:
        return f"# Scene `{scene}`\n\n`{errors_csv}` is damaged ({defect}); `{rebuild(errors_csv)}` rebuilds it.\n"
    errors = pd.read_csv(errors_csv, encoding="utf-8")
    norms = [c for c in errors.columns if c not in ("N", "h")]
    header = ["h", *(label_md(n) for n in norms)]
    lines = [f"# Scene `{scene}`", "", f"Errors ‖u − u_h‖ (`{errors_csv}`):", ""]
    lines.append(md_table(header, [[h_label(r["N"]), *(sci_md(float(r[n])) for n in norms)]
                                   for _, r in errors.iterrows()]))
    if eoc_csv is not None and Path(eoc_csv).exists() and (defect := table_defect(eoc_csv)) is not None:
        lines += ["", f"`{eoc_csv}` is damaged ({defect}) and not shown; `{rebuild(eoc_csv)}` rebuilds it."]
    elif eoc_csv is not None and Path(eoc_csv).exists():
        eoc = pd.read_csv(eoc_csv, dtype={"N": str}, encoding="utf-8")
        rows = [["regr." if r["N"] == "regression" else h_label(r["N"]), *(f"{float(r[n]):.3f}" for n in norms)]
                for _, r in eoc.iterrows()]
        lines += ["", f"EOCs of consecutive meshes and the regression slope (`{eoc_csv}`):", "", md_table(header, rows)]
    return "\n".join(lines)


def contents_markdown(studies: Sequence[Study], scenes: Sequence[str]) -> str:
    """The report's contents page: per study whether it was built here, is committed or missing."""
    lines = ["# Contents of this report", "",
             "Per study: computed on the machine that made this report from its results in `results/` "
             "(\"built on this machine\"); or, without those results, shown as the files are: the "
             "repository's committed files (the bytes of git's `HEAD`), or files that differ from them; "
             "or missing.", ""]
    lines += [f"- {s.status}" for s in studies]
    lines.append(f"- scenes with their errors and EOCs: {', '.join(scenes) if scenes else 'none built'}")
    return "\n".join(lines) + "\n"


def contents_text(config: Mapping, root: str | os.PathLike = ".") -> str:
    """The contents page's Markdown for the state of ``root`` now."""
    return contents_markdown(plan(root, config), built_scenes(root, config))


class _NoMissingMetadata(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return "Missing metadata for file" not in str(record.getMessage())


def hide_missing_metadata_warnings() -> None:
    """Drop Snakemake's report warning about each output no job of this checkout wrote (one per
    file of a committed or never-built study: hundreds after a fresh clone); ``plan`` states per
    study whether it was built here."""
    logging.getLogger("snakemake.logging").addFilter(_NoMissingMetadata())


def page_stage(out: str | os.PathLike, title: str, source: str | os.PathLike | None = None,
               scene: str | None = None, errors_csv: str | None = None, eoc_csv: str | None = None,
               text: str | None = None) -> None:
    """Stage of the report's page rules: Markdown ``text``, a Markdown file ``source`` or a
    scene's tables, as an HTML page."""
    from signorini.pipeline.artifacts import atomic_write_text

    if source is not None:
        text = Path(source).read_text(encoding="utf-8")
    elif scene is not None:
        text = scene_markdown(str(scene), str(errors_csv), eoc_csv)
    atomic_write_text(out, markdown_page(text, title))


def page_labels(file: str, **labels: str) -> dict[str, str]:
    """The labels of a page in the report: the ``file`` it shows (and any ``labels``), with view "page".

    Snakemake's report makes one menu row (and one search row) per distinct label tuple, so a page
    labelled like its Markdown file would replace that file's row, or the file the page's.  Only the
    pages carry ``view``: a label column holding exactly two values, each on half the rows (page and
    download), would be drawn as a switch over one row instead of two rows."""
    return {**labels, "file": file, "view": "page"}


def digest(*files: str | os.PathLike) -> str:
    """The SHA-256 of the files' contents (a page rule's parameter: a changed source reruns it)."""
    h = hashlib.sha256()
    for f in files:
        h.update(Path(f).read_bytes() if Path(f).exists() else b"")
    return h.hexdigest()


# --- what exists, what was built here ---------------------------------------------------------


def _evidence(target: str, config: Mapping) -> list[str]:
    """The cached artifacts a target's outputs are rendered from (their existence in ``results/``
    is what "built here" means; the committed outputs come without them)."""
    from signorini.fem.norms.names import true_name
    from signorini.published import TABLE2_NORMS

    scenes, fig = config["scenes"], config.get("figures_scene", "paper")
    if target == "all":
        return [paths.PATHS[k].format(scene=fig) for k in ("errors_csv", "eoc_csv")]
    if target in ("true_norms", "fine", "finest"):
        scene = fig if target == "true_norms" else target
        listed = scenes[scene].get("norms") or TABLE2_NORMS  # the scene defaults: Table 2's norms
        return [paths.PATHS["norm_json"].format(scene=scene, N=N, norm=true_name(n))
                for N in scenes[scene]["N"] for n in TABLE2_NORMS if n in listed]
    if target == "theory":
        return [paths.PATHS["errors_csv"].format(scene="theory"),
                *(paths.PATHS["theory_json"].format(scene="theory", N=N) for N in scenes["theory"]["N"])]
    if target == "stability":
        from signorini.studies.stability.atlas import case_artifacts

        return case_artifacts(config, "stability", paths.PATHS["atlas_case_json"])
    # work precision: measurements on each mesh (its configurations depend on the installed solvers)
    measured = paths.PATHS["wp_measure_json"].replace("{solver}", "*")
    return [measured.format(scene="work_precision", N=N) for N in scenes["work_precision"]["N"]]


@dataclass
class Study:
    """One target in the report: its rendering rules whose outputs exist (``rules``), those whose
    outputs are missing (``missing``), whether this machine computed them from intact cached
    results (``built_here``), the damaged ones among those results (``damaged``: {file: why}), and
    otherwise whether the outputs hold the bytes of git's ``HEAD`` (``committed``; None without git)."""

    target: str
    rules: list[str] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    built_here: bool = False
    damaged: dict[str, str] = field(default_factory=dict)
    committed: bool | None = None

    @property
    def status(self) -> str:
        name, command = paths.TARGET_RULES[self.target].title, paths.TARGET_RULES[self.target].command
        if not self.rules:
            return f"{name}: not in the report, nothing built (`{command}`)"
        if self.built_here:
            origin = "built on this machine"
        elif self.committed:
            origin = (f"the repository's committed files (the bytes of git's HEAD), not computed on this machine "
                      f"(`{command}` computes them)")
        elif self.committed is None:
            origin = (f"the files as found, not computed from this machine's results; without git, whether they are "
                      f"the committed files is not known (`{command}` computes them)")
        else:
            origin = (f"files that differ from the repository's committed ones (computed or edited here), without "
                      f"their intact results in results/ (`{command}` recomputes them)")
        missing = f"; missing: {', '.join(self.missing)} (`{command}`)" if self.missing else ""
        return f"{name}: {origin}{missing}"


def rebuild(path: str | os.PathLike) -> str:
    """The command that rebuilds a cached artifact."""
    return f"snakemake -c2 {path}"


def damaged(root: str | os.PathLike, files: Sequence[str]) -> dict[str, str]:
    """{file: why} of the ``files`` (patterns with ``*`` allowed) under ``root`` that exist and fail
    their integrity check: a scene table's defect (``integrity.table_defect``), any other
    artifact's checksum (``integrity.artifact_ok``)."""
    from signorini.pipeline.integrity import artifact_ok, table_defect

    root, found = Path(root), {}
    for pattern in files:
        for path in sorted(root.glob(pattern)) if "*" in pattern else [root / pattern]:
            if not path.is_file():
                continue
            why = table_defect(path) if path.suffix == ".csv" else None if artifact_ok(path) else "fails its checksum"
            if why is not None:
                found[str(path.relative_to(root))] = why
    return found


def same_as_head(root: str | os.PathLike, files: Sequence[str]) -> bool | None:
    """Whether ``files`` (relative to ``root``) hold the bytes git's ``HEAD`` has for them: False
    when one is not in ``HEAD`` or differs; None without git or a repository."""
    import subprocess

    def git(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(["git", "-C", str(root), *args, "--", *files], capture_output=True, encoding="utf-8")

    try:
        tracked, diff = git("ls-tree", "-r", "--name-only", "HEAD"), git("diff", "--quiet", "HEAD")
    except OSError:
        return None
    if tracked.returncode != 0 or diff.returncode not in (0, 1):
        return None
    return set(tracked.stdout.splitlines()) >= set(files) and diff.returncode == 0


def _exists(root: Path, files: Sequence[str]) -> bool:
    """Every file exists (a pattern with ``*``: at least one file matches it)."""
    return all(any(root.glob(f)) if "*" in f else (root / f).exists() for f in files)


def plan(root: str | os.PathLike = ".", config: Mapping | None = None) -> list[Study]:
    """Per target (``paths.TARGETS``): its rendering rules whose outputs (and those of the rules
    they read, ``paths.RENDER_INPUTS``) all exist, and whether they were built here."""
    root = Path(root)
    if config is None:
        from signorini.pipeline.config import load_config

        config = load_config(root / "workflow/config.yaml")
    studies = []
    for target, rules in paths.TARGETS.items():
        study = Study(target)
        for rule in rules:
            needed = [rule, *paths.RENDER_INPUTS.get(rule, ())]
            ok = all(_exists(root, list(paths.FIGURES[r].values())) for r in needed)
            (study.rules if ok else study.missing).append(rule)
        if study.rules:  # the evidence of a study with nothing to show is not asked for (its scene may be gone)
            evidence = _evidence(target, config)
            study.damaged = damaged(root, evidence)
            study.built_here = _exists(root, evidence) and not study.damaged
        if study.rules and not study.built_here:
            study.committed = same_as_head(root, [f for rule in study.rules for f in paths.FIGURES[rule].values()])
        studies.append(study)
    return studies


def scene_tables(config: Mapping) -> list[str]:
    """Every configured scene's ``errors.csv`` and ``eoc.csv``."""
    return [paths.PATHS[key].format(scene=s) for s in config["scenes"] for key in ("errors_csv", "eoc_csv")]


def built_scenes(root: str | os.PathLike, config: Mapping) -> list[str]:
    """The configured scenes whose ``errors.csv`` exists and is intact (each gets a page of its tables)."""
    return [
        s for s in config["scenes"]
        if (Path(root) / (table := paths.PATHS["errors_csv"].format(scene=s))).exists() and not damaged(root, [table])
    ]


def pages(root: str | os.PathLike, studies: Sequence[Study], config: Mapping) -> list[str]:
    """The report's pages: one per existing Markdown output of an included rule, one per built scene."""
    included = {f for s in studies for rule in s.rules for f in paths.FIGURES[rule].values()}
    out = [paths.report_page(p) for p, src in paths.REPORT_PAGES.items() if src in included]
    return out + [paths.REPORT_SCENE_PAGE.format(scene=s) for s in built_scenes(root, config)]


def files(studies: Sequence[Study]) -> list[str]:
    """The included rules' own outputs (figures, CSV, LaTeX, PDF): Snakemake's report shows them."""
    return [f for s in studies for rule in s.rules for f in paths.FIGURES[rule].values()]


def _snakemake(*args: str) -> int:
    """Run this environment's Snakemake in the working directory; its errors are shown."""
    import subprocess

    exe = Path(sys.executable).with_name("snakemake")
    return subprocess.run([str(exe) if exe.exists() else "snakemake", *args]).returncode


def build(out: str = "results/report.html", config_path: str = "workflow/config.yaml") -> int:
    """``make report``: say what the report shows, render its pages, write the report."""
    from signorini.pipeline.config import load_yaml

    config = load_yaml(config_path)
    studies = plan(".", config)
    scenes = built_scenes(".", config)
    broken = {**damaged(".", scene_tables(config)), **{f: why for s in studies for f, why in s.damaged.items()}}
    for path, why in broken.items():  # left out of the report; the rest is reported
        print(f"skipped {path}: damaged ({why}); `{rebuild(path)}` rebuilds it")
    print(f"{out} shows:")
    for s in studies:
        print(f"  {s.status}")
    print(f"  scenes with their errors and EOCs: {', '.join(scenes) if scenes else 'none built'}")
    page_targets = [paths.REPORT_CONTENTS, *pages(".", studies, config)]
    if not any(s.rules for s in studies) and not scenes:
        print("nothing to report: run `make all` first", file=sys.stderr)
        return 1
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    print(f"rendering the report's pages ({paths.REPORT_DIR}/*.html), then the report ...", flush=True)
    rc = _snakemake("-c1", *page_targets, "--quiet", "all")
    if rc == 0:
        rc = _snakemake("--report", out, *page_targets, *files(studies), "--quiet", "all")
    print(f"report: {out} (open it in a browser)" if rc == 0 else f"the report failed (exit status {rc})")
    return rc


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m signorini.studies.report [build | status | targets]``: ``build`` (``make
    report``) writes ``results/report.html``; ``status`` prints what it would show, ``targets``
    the files of ``snakemake --report``."""
    parser = argparse.ArgumentParser(prog="python -m signorini.studies.report")
    parser.add_argument("what", nargs="?", default="build", choices=("build", "status", "targets"))
    parser.add_argument("--out", default="results/report.html")
    args = parser.parse_args(argv)
    if args.what == "build":
        return build(args.out)
    from signorini.pipeline.config import load_config

    config = load_config("workflow/config.yaml")
    studies = plan(".", config)
    if args.what == "status":
        for s in studies:
            print(s.status)
        return 0
    print(" ".join([paths.REPORT_CONTENTS, *pages(".", studies, config), *files(studies)]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
