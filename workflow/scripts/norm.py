"""rule norm: one norm of u - u_h for one scene and N."""

from signorini.pipeline import job_log, norm_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    norm_stage(
        snakemake.params.problem,
        int(snakemake.wildcards.N),
        snakemake.input.solution,
        snakemake.wildcards.norm,
        snakemake.output[0],
        diagonal=snakemake.params.diagonal,
        conventions=snakemake.params.conventions,
    )
