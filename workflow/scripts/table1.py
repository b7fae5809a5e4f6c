"""rule table1: paper_figures/table1.{csv,md,tex}."""

from signorini.pipeline import job_log, read_errors
from signorini.tables import table1

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    errors = read_errors(snakemake.params.N, snakemake.params.norm_jsons)
    table1(errors, snakemake.output.csv, snakemake.output.md, snakemake.output.tex)
