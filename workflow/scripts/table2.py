"""rule table2: paper_figures/table2.{csv,md,tex}."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.tables import table2_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p = snakemake.params
    table2_stage(snakemake.input.eoc[0], p.N, p.norm_jsons, snakemake.output)
