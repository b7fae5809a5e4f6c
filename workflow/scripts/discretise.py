"""rule discretise: mesh and assembly of (S_h) for one scene and N."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.discretise import discretise_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    p, o = snakemake.params, snakemake.output
    discretise_stage(p.problem, int(snakemake.wildcards.N), p.diagonal, o.npz, o.json)
