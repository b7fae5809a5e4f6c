"""rule table2: paper_figures/table2.{csv,md,tex}."""

from signorini.pipeline import job_log, read_errors_csv
from signorini.tables import table2

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    eoc = read_errors_csv(snakemake.input.eoc)
    table2(eoc, snakemake.params.N, snakemake.output.csv, snakemake.output.md, snakemake.output.tex)
