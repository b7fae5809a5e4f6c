"""rules report_<page> and report_scene: results/report/<page>.html, a Markdown output (or a
scene's errors and EOCs) as an HTML page that the Snakemake report shows inline."""

from signorini.pipeline.joblog import job_log
from signorini.studies.report import page_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    page_stage(snakemake.output.html, **snakemake.params.page)
