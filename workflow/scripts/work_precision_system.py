"""rule work_precision_system: the assembled system of one mesh, cached for the study's jobs."""

from signorini.pipeline import job_log
from signorini.work_precision import system_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    system_stage(
        snakemake.params.problem,
        int(snakemake.wildcards.N),
        snakemake.params.diagonal,
        snakemake.output.npz,
        snakemake.output.json,
    )
