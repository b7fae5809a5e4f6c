"""rule work_precision_table: paper_figures/work_precision.csv (every measurement)."""

from signorini.pipeline import job_log
from signorini.work_precision import collect_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    collect_stage(snakemake.input.jsons, snakemake.output[0])
