"""rule table1: paper_figures/table1.{csv,md,tex}."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.tables import table1_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    table1_stage(snakemake.params.N, snakemake.params.norm_jsons, snakemake.output)
