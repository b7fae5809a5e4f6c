"""rule norm: one norm of u - u_h for one scene and N."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.norm import norm_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    p, wc = snakemake.params, snakemake.wildcards
    norm_stage(
        p.problem, int(wc.N), p.diagonal, snakemake.input.solution, wc.norm, snakemake.output.json, p.conventions
    )
