# The report's pages (make report; signorini.studies.report): every Markdown output, and each
# scene's errors and EOCs, as an HTML page, which Snakemake's report shows inline (other text
# files it offers only as downloads). A page renders the file as it is: its source is a parameter
# with its digest (an edited source reruns the page), not an input, so that rendering the
# committed findings of a study never recomputes the study. Not part of any study's target.
# A page's labels are its source file's name and view "page" (report_lib.page_labels): the
# report's menu and search list the page and the file's download as two rows.
from signorini.studies import report as report_lib

# each page (paths.REPORT_PAGE_ENTRIES): its source, and its caption and place in the menu
for _page, _entry in paths.REPORT_PAGE_ENTRIES.items():
    _source, _caption, _category, _subcategory = _entry

    rule:
        """A Markdown output as an HTML page of the report."""
        name:
            f"report_{_page}"
        input:
            code=code("report_page"),
        output:
            html=report(
                paths.report_page(_page),
                caption=f"../report/{_caption}.rst",
                category=_category,
                subcategory=_subcategory,
                labels=report_lib.page_labels(Path(_source).name),
            ),
        log:
            paths.log("scene", f"report_{_page}", scene="report"),
        localrule: True
        conda:
            "../envs/signorini.yaml"
        params:
            page={"source": _source, "title": Path(_source).name},
            digest=lambda wc, source=_source: report_lib.digest(source),
        script:
            "../scripts/report_page.py"


rule report_scene:
    """A scene's errors and EOCs as an HTML page of the report."""
    input:
        code=code("report_page"),
    output:
        html=report(
            paths.REPORT_SCENE_PAGE,
            caption="../report/errors.rst",
            category="Scenes",
            subcategory="{scene}",
            labels=report_lib.page_labels("errors and EOCs", scene="{scene}"),
        ),
    log:
        paths.log("scene", "report_scene"),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        page=lambda wc: {
            "scene": wc.scene,
            "title": f"scene {wc.scene}",
            "errors_csv": PATHS["errors_csv"].format(scene=wc.scene),
            "eoc_csv": PATHS["eoc_csv"].format(scene=wc.scene),
        },
        digest=lambda wc: report_lib.digest(
            PATHS["errors_csv"].format(scene=wc.scene),
            PATHS["eoc_csv"].format(scene=wc.scene),
        ),
    script:
        "../scripts/report_page.py"


rule report_contents:
    """The report's contents: per study, built here, committed or missing."""
    input:
        code=code("report_page"),
    output:
        html=report(
            paths.REPORT_CONTENTS,
            caption="../report/contents.rst",
            category="Report contents",
            labels=report_lib.page_labels("contents"),
        ),
    log:
        paths.log("scene", "report_contents", scene="report"),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        # the text itself: a change of state reruns the page
        page=lambda wc: {"text": report_lib.contents_text(config), "title": "contents"},
    script:
        "../scripts/report_page.py"


# Snakemake's report warns once per output in the DAG that no job of this checkout wrote
# (hundreds after a fresh clone); the contents page and `make report` say it per study instead
if "--report" in sys.argv:
    report_lib.hide_missing_metadata_warnings()
