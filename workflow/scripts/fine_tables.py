"""rules fine_tables and finest_tables: paper_figures/table{1,2}_{fine,finest}.{csv,md}."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.true_tables import CONTINUED_TARGETS, true_tables_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    i = snakemake.input
    true_tables_stage(snakemake.params.N, snakemake.params.norm_jsons, i.paper_table1, snakemake.output,
                      CONTINUED_TARGETS[snakemake.params.scene])
