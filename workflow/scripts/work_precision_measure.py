"""rule work_precision_measure: one solver configuration at all its tolerances on one mesh."""

from signorini.pipeline import job_log
from signorini.work_precision import measure_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    p = snakemake.params
    measure_stage(
        p.problem,
        int(snakemake.wildcards.N),
        p.config,
        p.tolerances,
        p.time_limit_s,
        snakemake.input.system,
        snakemake.input.system_json,
        snakemake.input.exact,
        p.disc_norm_jsons,
        snakemake.output[0],
        prev_json=snakemake.input.prev or None,
        diagonal=p.diagonal,
        conventions=p.conventions,
        growth_exponent=p.growth_exponent,
    )
