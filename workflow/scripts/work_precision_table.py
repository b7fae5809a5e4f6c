"""rule work_precision_table: paper_figures/work_precision.csv (every measurement)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.work_precision.table import table_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    table_stage(snakemake.input.jsons, snakemake.output.csv)
