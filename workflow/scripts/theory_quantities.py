"""rule theory_quantities: supercloseness, discrete H^{1/2} norm, contact set for one scene and N."""

from signorini.pipeline import job_log, theory_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    theory_stage(
        snakemake.params.problem,
        int(snakemake.wildcards.N),
        snakemake.input.solution,
        snakemake.output[0],
        diagonal=snakemake.params.diagonal,
    )
