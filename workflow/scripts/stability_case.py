"""rule stability_case: one case of the stability atlas, every solver column."""

from signorini.pipeline.joblog import job_log
from signorini.studies.stability.cases import case_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    case_stage(snakemake.params.job, snakemake.output.json, snakemake.output.npz)
