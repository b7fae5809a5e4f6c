"""rule meshes_report: paper_figures/meshes.{md,csv} and meshes_rates.{pdf,png}."""

from signorini.pipeline.joblog import job_log
from signorini.studies.meshes.report import meshes_report_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    meshes_report_stage(snakemake.params.scenes, snakemake.params.reference, snakemake.output)
