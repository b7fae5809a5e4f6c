"""rule theory_report: findings, table, rates data and figures of the theory scene."""

from signorini.pipeline.joblog import job_log
from signorini.studies.theory.report import report_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    report_stage(
        snakemake.input.errors[0],
        snakemake.input.theory,
        snakemake.output,
        snakemake.params.true_norm_jsons,
        snakemake.input.contact_set,
    )
