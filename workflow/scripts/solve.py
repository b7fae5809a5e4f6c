"""rule solve: mesh, assemble and solve (S_h) for one scene and N."""

from signorini.pipeline import job_log, solve_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    solve_stage(
        snakemake.params.problem,
        int(snakemake.wildcards.N),
        snakemake.params.solver,
        snakemake.output.npz,
        snakemake.output.json,
        diagonal=snakemake.params.diagonal,
        solver_options=snakemake.params.solver_options,
    )
