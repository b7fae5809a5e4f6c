"""rule errors: results/<scene>/errors.csv from the per-norm artifacts."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.error_table import errors_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    errors_stage(snakemake.params.N, snakemake.params.norm_jsons, snakemake.output.csv)
