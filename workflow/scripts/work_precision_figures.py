"""rule work_precision_figures: work_precision.{pdf,png} and cost_of_accuracy.{pdf,png}."""

from signorini.pipeline.joblog import job_log
from signorini.studies.work_precision.figures import figures_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    figures_stage(snakemake.input.csv, snakemake.params.figure_N, snakemake.output)
