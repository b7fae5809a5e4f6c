"""rule errors: results/<scene>/errors.csv from the per-norm artifacts."""

from signorini.pipeline import collect_errors, job_log

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    collect_errors(snakemake.params.N, snakemake.params.norm_jsons, snakemake.output[0])
