"""rule solve: solve (S_h) of one scene and N on its assembled system."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p, o = snakemake.params, snakemake.output
    solve_stage(SceneMesh.of_job(snakemake), snakemake.input.system, p.solver, o.npz, o.json, p.solver_options)
