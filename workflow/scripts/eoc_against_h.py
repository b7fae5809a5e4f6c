"""rule eoc_against_h: paper_figures/eoc_against_h.{pdf,png} (EOCs of Table 2's norms to h = 1/4001)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.eoc_figure import eoc_against_h_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    i = snakemake.input
    eoc_against_h_stage(i.true_table1, i.fine_table1, snakemake.output)
