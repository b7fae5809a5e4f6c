"""rule theory_report: findings, table and figures of the theory scene."""

from signorini.pipeline import job_log
from signorini.theory_report import theory_report

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    theory_report(
        snakemake.input.errors,
        snakemake.input.theory,
        snakemake.output.md,
        snakemake.output.csv,
        snakemake.output.rates_pdf,
        snakemake.output.rates_png,
        snakemake.output.extra_pdf,
        snakemake.output.extra_png,
    )
