"""rule norm: one norm of u - u_h for one scene and N."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    at, i, o = SceneMesh.of_job(snakemake), snakemake.input, snakemake.output
    norm_stage(at, i.solution, snakemake.wildcards.norm, o.json, snakemake.params.conventions)
