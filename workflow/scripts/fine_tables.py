"""rule fine_tables: paper_figures/table1_fine.{csv,md} and table2_fine.{csv,md}."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.true_tables import FINE_TARGET, true_tables_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    i = snakemake.input
    true_tables_stage(snakemake.params.N, snakemake.params.norm_jsons, i.paper_table1, snakemake.output, FINE_TARGET)
